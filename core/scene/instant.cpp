// Resolving an instant against a file's valid times.
#include "scene/instant.hpp"

#include <cstdio>

#include "scene/framing.hpp"

namespace cv::core {

bool times_known(const std::vector<ValidTime>& times) {
  if (times.empty()) return false;
  for (const ValidTime& t : times) {
    if (t.iso_utc.find('T') == std::string::npos) return false;
  }
  return true;
}

void check_time_axis(const std::vector<ValidTime>& times, const std::string& source) {
  for (std::size_t i = 1; i < times.size(); ++i) {
    if (times[i].unix_s > times[i - 1].unix_s) continue;
    throw TimeError(source + ": the valid times are " + (times[i].unix_s == times[i - 1].unix_s ? "duplicated" : "not ascending") +
                    ": step " + std::to_string(i - 1) + " is " + times[i - 1].iso_utc + " and step " + std::to_string(i) + " is " +
                    times[i].iso_utc + ", expected strictly ascending times");
  }
}

std::string format_iso_utc(std::int64_t unix_s) {
  std::int64_t days = unix_s / 86400, secs = unix_s % 86400;
  if (secs < 0) secs += 86400, --days;
  // Civil date from days since 1970-01-01 (Howard Hinnant's algorithm, written out here).
  days += 719468;
  const std::int64_t era = (days >= 0 ? days : days - 146096) / 146097;
  const std::int64_t doe = days - era * 146097;
  const std::int64_t yoe = (doe - doe / 1460 + doe / 36524 - doe / 146096) / 365;
  std::int64_t y = yoe + era * 400;
  const std::int64_t doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
  const std::int64_t mp = (5 * doy + 2) / 153;
  const std::int64_t d = doy - (153 * mp + 2) / 5 + 1;
  const std::int64_t m = mp < 10 ? mp + 3 : mp - 9;
  if (m <= 2) ++y;
  char buf[128];
  std::snprintf(buf, sizeof buf, "%04lld-%02lld-%02lldT%02lld:%02lld:%02lldZ", static_cast<long long>(y), static_cast<long long>(m),
                static_cast<long long>(d), static_cast<long long>(secs / 3600), static_cast<long long>(secs / 60 % 60),
                static_cast<long long>(secs % 60));
  return buf;
}

std::string time_range_text(const std::vector<ValidTime>& times) {
  if (times.empty()) return "no time steps";
  return times.front().iso_utc + " .. " + times.back().iso_utc + " (" + std::to_string(times.size()) + " step" +
         (times.size() == 1 ? "" : "s") + ")";
}

Instant instant_at_step(const std::vector<ValidTime>& times, std::size_t step, const std::string& source) {
  if (step >= times.size()) {
    throw TimeError(source + ": time step " + std::to_string(step) + ": found no such step, expected 0.." +
                    std::to_string(times.empty() ? 0 : times.size() - 1) + " (" + time_range_text(times) + ")");
  }
  Instant at;
  at.step0 = at.step1 = step;
  at.time_known = times[step].iso_utc.find('T') != std::string::npos;
  at.unix_s = times[step].unix_s;
  at.iso_utc = times[step].iso_utc;
  return at;
}

Instant instant_at_time(const std::vector<ValidTime>& times, const std::string& iso, const std::string& source) {
  const auto when = parse_iso_utc(iso);
  if (!when) throw TimeError(source + ": time '" + iso + "': expected a UTC date-time YYYY-MM-DDThh:mm:ssZ or a step index");
  if (!times_known(times)) {
    throw TimeError(source + ": time " + iso + ": the file has no UTC valid times (" + std::to_string(times.size()) +
                    " step(s) by index), expected a step index");
  }
  check_time_axis(times, source);
  if (*when < times.front().unix_s || *when > times.back().unix_s) {
    throw TimeError(source + ": time " + iso + " is outside the file's times " + time_range_text(times) +
                    ", expected an instant within them");
  }
  Instant at;
  at.time_known = true;
  at.unix_s = *when;
  at.iso_utc = format_iso_utc(*when);
  std::size_t i = 0;
  while (i + 1 < times.size() && times[i + 1].unix_s <= *when) ++i;
  at.step0 = i;
  if (times[i].unix_s == *when || i + 1 >= times.size()) {
    at.step1 = i;
    return at;
  }
  at.step1 = i + 1;
  at.gap_s = double(times[i + 1].unix_s - times[i].unix_s);
  at.fraction = double(*when - times[i].unix_s) / at.gap_s;
  return at;
}

}  // namespace cv::core
