// How many iterations a loop of u_second runs after a loop of u_first in the same invocation. On
// Mesa's llvmpipe every loop of an invocation draws on one budget of 65 535 iterations
// (LP_MAX_TGSI_LOOP_ITERATIONS in gallivm), after which each loop runs its body once: the reason
// raymarch.comp marches in several dispatches (tests/render/loop_budget_test.cpp).
layout(local_size_x = 1) in;
layout(std430, binding = 0) writeonly buffer Counts { int counts[]; };

uniform int u_first;
uniform int u_second;

void main() {
  int a = 0;
  for (int i = 0; i < u_first; ++i) a += (i & 3) == 0 ? 1 : 0;
  int b = 0;
  for (int j = 0; j < u_second; ++j) ++b;
  counts[0] = a;
  counts[1] = b;
}
