// `cloudviewer compare A B`: two sources side by side on their own grids and on an explicit common
// grid (core/analysis/compare), with where cloud is in A only, B only or both and the B - A maps.
#include <algorithm>
#include <array>
#include <utility>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <optional>
#include <stdexcept>

#include "analysis/compare.hpp"
#include "analysis_commands.hpp"
#include "analysis_common.hpp"
#include "kernel/prepared_volume.hpp"
#include "physics/physics.hpp"
#include "plots/drape.hpp"
#include "render/context.hpp"
#include "render/frame_renderer.hpp"
#include "render/image_output.hpp"
#include "scene/framing.hpp"
#include "scene/quality.hpp"

namespace cv::cli {

using namespace analysis;

const char* compare_usage() {
  return "  compare A B -o OUT.png [--times T | TA,TB] [--csv OUT.csv] [--render OUT3D.png] [--render-maps MAPS.png]\n"
         "          [--render-size WxH]\n"
         "                           two sources side by side, each on its own grid (cloud cover, labelled with the source\n"
         "                           and valid time), and on a common grid, stated in the image and printed: the coarser\n"
         "                           spacing of the two on each axis over the region and altitudes both hold; there, the\n"
         "                           columns with cloud in A only, B only or both, and maps of B - A of cover, optical\n"
         "                           depth, cloud base and top with a diverging colour map; --times: one of each file's\n"
         "                           valid times or steps (default: the first valid time both hold); --csv: per column\n"
         "                           presence, the maps and their differences; --render: the difference view rendered on\n"
         "                           the GPU, the clouds of the common grid lit by the sun at noon over the view, their\n"
         "                           light coloured orange where cloud is in A only, blue in B only and white in both\n"
         "                           (the hue only: each keeps its own brightness), at --render-size (default 960x540);\n"
         "                           --render-maps: the four B - A maps draped on the globe as the same camera sees it,\n"
         "                           each at half that size, with the diverging colour map and bars of -o's maps\n";
}

namespace {

// A 2-D map of a grid's columns into an area of the canvas over (lat_lo..lat_hi, lon_lo..lon_hi):
// each pixel takes the nearest column.
void draw_map(Canvas& cv, const Area& a, const core::VolumeGrid& g, double lat_lo, double lat_hi, double lon_lo, double lon_hi,
              const std::function<Rgb(std::size_t column)>& colour) {
  for (int y = 0; y < a.h(); ++y) {
    const double lat = lat_hi - (y + 0.5) / a.h() * (lat_hi - lat_lo);
    for (int x = 0; x < a.w(); ++x) {
      const double lon = lon_lo + (x + 0.5) / a.w() * (lon_hi - lon_lo);
      const std::optional<std::size_t> col = column_at(g, lat, lon);
      cv.set(a.x0 + x, a.y0 + y, col ? colour(*col) : kNoData);
    }
  }
  cv.box(a.x0 - 1, a.y0 - 1, a.x1 + 1, a.y1 + 1, kInk);
}

// The B - A maps: each with its name, values and the scale shown; `range` is the largest magnitude
// (1 when all are zero: a bar of +-1, the map all white), so 0 is white and the bar symmetric.
struct Diff {
  const char* name;
  const std::vector<float>* d;
  double scale;
  double range = 1.0;
};
std::array<Diff, 4> difference_maps(const core::Comparison& cmp) {
  std::array<Diff, 4> diffs = {Diff{"B-A cover", &cmp.d_cover, 1.0}, Diff{"B-A optical depth", &cmp.d_optical_depth, 1.0},
                               Diff{"B-A base km", &cmp.d_base_m, 1e-3}, Diff{"B-A top km", &cmp.d_top_m, 1e-3}};
  for (Diff& k : diffs) {
    double most = 0.0;
    for (float x : *k.d)
      if (std::isfinite(x)) most = std::max(most, std::abs(double(x)) * k.scale);
    k.range = most > 0.0 ? most : 1.0;
  }
  return diffs;
}
Rgb diff_colour(const Diff& k, std::size_t column) {
  const float x = (*k.d)[column];
  return std::isfinite(x) ? diverging_colour(0.5 + 0.5 * x * k.scale / k.range) : kNoData;
}

// The four maps draped on the globe as the difference view's camera (auto_camera over the common
// grid at w x h) sees them, in a 2 x 2 grid, each with its title and colour bar.
std::vector<unsigned char> draped_maps(const core::Comparison& cmp, int w, int h, int& out_w, int& out_h) {
  const int right = 80, title = 24, pad = 10;
  out_w = pad + 2 * (w + right);
  out_h = pad + 2 * (h + title) + 20;
  Canvas cv(out_w, out_h, kPaper);
  const core::Camera cam = core::auto_camera(cmp.grid, w, h);
  const std::array<Diff, 4> diffs = difference_maps(cmp);
  for (int k = 0; k < 4; ++k) {
    const int x0 = pad + (k % 2) * (w + right), y0 = title + (k / 2) * (h + title);
    const Diff& d = diffs[static_cast<std::size_t>(k)];
    drape_columns(cv, x0, y0, cam, cmp.grid, [&](std::size_t c) { return diff_colour(d, c); });
    cv.text(x0, y0 - 8, 9, std::string(d.name) + " on the globe", kInk);
    colour_bar(cv, x0 + w + 8, y0 + 12, x0 + w + 18, y0 + h - 1, -d.range, d.range, "", diverging_colour);
  }
  cv.text(pad, out_h - 8, 9, "light grey: no data, or no cloud in one of them", kInk);
  return cv.rgb();
}

// The false colours of the rendered difference view (march.tint_liquid and tint_ice): their mean is
// grey, so cloud in both, half in each component, is white.
constexpr glm::dvec3 kTintA{1.0, 0.525, 0.05}, kTintB{0.05, 0.525, 1.0};

// The difference view: the presence medium (core::presence_medium) on the common grid, rendered by
// the GPU march as `render` renders a volume (default quality, the camera framing the grid from the
// south, the sun at noon over it), A only orange, B only blue, both white, with a caption below.
std::vector<unsigned char> render_difference_view(const core::Comparison& cmp, const core::ValidTime& time, double r_eff_um, int width,
                                                  int height, const std::vector<std::string>& caption, int& out_h) {
  core::CloudVolume vol;
  vol.grid = cmp.grid;
  vol.times = {time};
  vol.liquid_r_eff_um = r_eff_um;
  for (core::Field f : {core::Field::CloudFraction, core::Field::ExtinctionLiquid, core::Field::ExtinctionIce}) {
    vol.has_field[static_cast<int>(f)] = true;
  }
  core::TimeStepData medium = core::presence_medium(cmp);
  vol.has_ground = !medium.ground_m.empty();
  const auto prepared = std::make_shared<const core::PreparedVolume>(core::prepare_volume(vol.grid, medium));
  vol.put(0, std::move(medium));
  core::Scene scene;
  scene.width = width, scene.height = height;
  core::apply_quality("default", scene.render);
  scene.render.march.quality.view_step_m = core::resolve_view_step_m(scene.render, vol.grid);
  scene.sun.mode = core::SunMode::LocalNoon;  // lit wherever the view is: a comparison, not a forecast
  core::MediumSettings& m = scene.render.march.medium;
  m.droplet_diameter_um = 2.0 * r_eff_um;
  // One phase function for both components: A and B differ in colour only, not in how they scatter.
  m.liquid_phase_hg = true;
  m.ice_g = physics::f64::mie_mean_cosine(physics::f64::mie_params(m.droplet_diameter_um));
  m.tint_liquid = kTintA;
  m.tint_ice = kTintB;
  auto ctx = render::make_headless_context();
  const render::ShaderLoader loader({render::ShaderLoader::default_shader_dir()});
  render::FrameRenderer renderer(loader);
  renderer.use_volume(prepared);
  const core::FrameSpec frame = render::resolve_frame(scene, vol);
  std::vector<glm::vec4> marched;
  const std::vector<glm::vec4> pixels = renderer.render(frame, {}, {}, &marched);
  render::ToneSettings tone;
  tone.exposure = render::auto_exposure(marched);
  if (frame.march.features.atmosphere || frame.march.features.globe) tone.background = glm::dvec3(0.0);
  const std::vector<unsigned char> rgb8 = render::tonemap_srgb8(pixels, tone);
  const int band = 28 + 14 * static_cast<int>(caption.size());
  out_h = height + band;
  Canvas cv(width, out_h, kPaper);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const std::size_t i = 3 * (static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x));
      cv.set(x, y, Rgb{rgb8[i], rgb8[i + 1], rgb8[i + 2]});
    }
  const Rgb swatch[3] = {{255, 134, 13}, {13, 134, 255}, {235, 235, 235}};
  const char* label[3] = {"A only", "B only", "both"};
  for (int k = 0; k < 3; ++k) {
    const int x0 = 8 + k * 90, y0 = height + 8;
    for (int y = 0; y < 10; ++y)
      for (int x = 0; x < 14; ++x) cv.set(x0 + x, y0 + y, swatch[k]);
    cv.box(x0, y0, x0 + 13, y0 + 9, kInk);
    cv.text(x0 + 20, y0 + 9, 9, label[k], kInk);
  }
  for (std::size_t k = 0; k < caption.size(); ++k) cv.text(8, height + 32 + 14 * static_cast<int>(k), 9, caption[k], kInk);
  return cv.rgb();
}

std::size_t resolve_in(const core::CloudVolume& vol, const std::string& file, const std::string& t) {
  Common c{"compare", file, t};
  return resolve_step(vol, c);
}

}  // namespace

int cmd_compare(const std::vector<std::string>& args) {
  std::vector<std::string> files;
  std::string out, csv, times, render_out, maps_out;
  int render_w = 960, render_h = 540;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (!a.empty() && a[0] == '-') {
      if (i + 1 >= args.size()) throw UsageError{"cloudviewer compare: " + a + ": expected a value after it"};
      const std::string& v = args[++i];
      if (a == "-o") out = v;
      else if (a == "--csv") csv = v;
      else if (a == "--times") times = v;
      else if (a == "--render") render_out = v;
      else if (a == "--render-maps") maps_out = v;
      else if (a == "--render-size") {
        if (std::sscanf(v.c_str(), "%dx%d", &render_w, &render_h) != 2 || render_w < 16 || render_h < 16 || render_w > 8192 ||
            render_h > 8192 || v.find_first_not_of("0123456789x") != std::string::npos) {
          throw UsageError{"cloudviewer compare: --render-size: found '" + v + "', expected WxH with 16..8192 each"};
        }
      }
      else throw UsageError{"cloudviewer compare: unknown option '" + a + "'"};
    } else {
      files.push_back(a);
    }
  }
  if (files.size() != 2 || out.empty()) throw UsageError{"cloudviewer compare: expected two files A B and -o OUT.png"};
  check_outputs("compare", out, csv, files[0]);
  check_outputs("compare", out, csv, files[1]);
  for (const auto& [path, flag] : {std::pair{render_out, "--render"}, std::pair{maps_out, "--render-maps"}}) {
    if (path.empty()) continue;
    for (const std::string& f : files) {
      core::check_output_extension(path, flag, {".png"});
      core::check_output_path(path, flag);
      core::check_output_not_input(path, flag, f, "an input");
    }
    if (path == out || (path == maps_out && path == render_out)) {
      throw UsageError{"cloudviewer compare: " + std::string(flag) + ": found '" + path + "', a file another output writes; expected its own PNG"};
    }
  }
  core::CloudVolume va = load(files[0]), vb = load(files[1]);
  // The steps compared.
  std::size_t sa = 0, sb = 0;
  if (!times.empty()) {
    const std::size_t comma = times.find(',');
    sa = resolve_in(va, files[0], comma == std::string::npos ? times : times.substr(0, comma));
    sb = resolve_in(vb, files[1], comma == std::string::npos ? times : times.substr(comma + 1));
  } else if (core::times_known(va.times) && core::times_known(vb.times)) {
    bool found = false;
    for (std::size_t i = 0; i < va.times.size() && !found; ++i)
      for (std::size_t j = 0; j < vb.times.size() && !found; ++j)
        if (va.times[i].unix_s == vb.times[j].unix_s) sa = i, sb = j, found = true;
    if (!found) {
      throw UsageError{"cloudviewer compare: A and B share no valid time: " + files[0] + " holds " + core::time_range_text(va.times) + ", " +
                       files[1] + " holds " + core::time_range_text(vb.times) + "; expected a common one, or --times TA,TB"};
    }
  }
  const core::Overlap o = core::grid_overlap(va.grid, vb.grid);
  if (o.empty) {
    throw UsageError{"cloudviewer compare: A and B share no region: " + files[0] + " holds " + core::grid_extent_text(va.grid) + " (altitude " +
                     num(va.grid.alt_m.start, "%.0f") + ".." + num(va.grid.alt_m.last(), "%.0f") + " m), " + files[1] + " holds " +
                     core::grid_extent_text(vb.grid) + " (altitude " + num(vb.grid.alt_m.start, "%.0f") + ".." + num(vb.grid.alt_m.last(), "%.0f") +
                     " m); expected an overlap"};
  }
  const core::TimeStepData& da = va.step(sa);
  const core::TimeStepData& db = vb.step(sb);
  const auto t0 = std::chrono::steady_clock::now();
  const core::VolumeGrid common = core::common_grid(va.grid, vb.grid, o);
  const core::Comparison cmp = core::compare_steps(va.grid, da, vb.grid, db, common);
  const double build_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  const std::string grid_line = core::common_grid_text(common, va.grid, vb.grid);
  std::size_t count[4] = {0, 0, 0, 0};
  for (core::Presence p : cmp.columns) ++count[static_cast<int>(p)];
  std::printf("A: %s at %s; B: %s at %s\n%s\ncolumns with cloud: A only %zu, B only %zu, both %zu, neither %zu; difference grid built in %.1f ms\n",
              files[0].c_str(), va.times[sa].iso_utc.c_str(), files[1].c_str(), vb.times[sb].iso_utc.c_str(), grid_line.c_str(), count[1],
              count[2], count[3], count[0], build_ms);
  // The picture: the two sources on their own grids and the presence map above, the differences below.
  const int pw = 220, ph = 150, gap = 70, left = 20, top = 50;
  const int width = left + 4 * (pw + gap), height = top + 2 * (ph + gap) + 60;
  Canvas cv(width, height, kPaper);
  auto area = [&](int col, int row) { return Area{left + col * (pw + gap), top + row * (ph + gap), left + col * (pw + gap) + pw - 1, top + row * (ph + gap) + ph - 1}; };
  auto own = [&](int col, core::CloudVolume& v, std::size_t step, const std::string& label) {
    const core::TimeStepData& d = v.step(step);
    const auto& g = v.grid;
    const Area a = area(col, 0);
    const double lon_hi = g.wraps_lon() ? g.lon_deg.start + 360.0 : g.lon_deg.last();
    draw_map(cv, a, g, g.lat_deg.start, g.lat_deg.last(), g.lon_deg.start, lon_hi, [&](std::size_t c) {
      const float x = d.maps.cloud_cover[c];
      return std::isfinite(x) ? sequential_colour(x) : kNoData;
    });
    cv.text(a.x0, a.y0 - 22, 9, label, kInk);
    cv.text(a.x0, a.y0 - 8, 9, "cover " + v.times[step].iso_utc, kInk);
  };
  own(0, va, sa, "A " + std::filesystem::path(files[0]).filename().string());
  own(1, vb, sb, "B " + std::filesystem::path(files[1]).filename().string());
  colour_bar(cv, area(1, 0).x1 + 8, area(1, 0).y0 + 12, area(1, 0).x1 + 18, area(1, 0).y1, 0.0, 1.0, "cover", sequential_colour);
  const Rgb only_a{230, 120, 20}, only_b{30, 110, 220}, both{90, 90, 90}, neither{245, 245, 245};
  const Area pa = area(2, 0);
  draw_map(cv, pa, common, common.lat_deg.start, common.lat_deg.last(), common.lon_deg.start,
           common.wraps_lon() ? common.lon_deg.start + 360.0 : common.lon_deg.last(), [&](std::size_t c) {
             switch (cmp.columns[c]) {
               case core::Presence::OnlyA: return only_a;
               case core::Presence::OnlyB: return only_b;
               case core::Presence::Both: return both;
               default: return neither;
             }
           });
  cv.text(pa.x0, pa.y0 - 22, 9, "cloud on the common grid", kInk);
  const Area la = area(3, 0);
  const std::pair<Rgb, std::string> keys[] = {{only_a, "A only"}, {only_b, "B only"}, {both, "both"}, {neither, "neither"}};
  for (int k = 0; k < 4; ++k) {
    for (int y = 0; y < 10; ++y)
      for (int x = 0; x < 14; ++x) cv.set(la.x0 + x, la.y0 + k * 18 + y, keys[k].first);
    cv.box(la.x0, la.y0 + k * 18, la.x0 + 13, la.y0 + k * 18 + 9, kInk);
    cv.text(la.x0 + 20, la.y0 + k * 18 + 9, 9, keys[k].second, kInk);
  }
  char gl[160];
  std::snprintf(gl, sizeof gl, "common grid %dx%dx%d", common.lon_deg.count, common.lat_deg.count, common.alt_m.count);
  cv.text(la.x0, la.y0 + 90, 9, gl, kInk);
  std::snprintf(gl, sizeof gl, "step %.3g deg %.3g deg %.0f m", common.lon_deg.step, common.lat_deg.step, common.alt_m.step);
  cv.text(la.x0, la.y0 + 104, 9, gl, kInk);
  cv.text(la.x0, la.y0 + 118, 9, "the coarser of A and B", kInk);
  const std::array<Diff, 4> diffs = difference_maps(cmp);
  for (int k = 0; k < 4; ++k) {
    const Diff& d = diffs[static_cast<std::size_t>(k)];
    const Area a = area(k, 1);
    draw_map(cv, a, common, common.lat_deg.start, common.lat_deg.last(), common.lon_deg.start,
             common.wraps_lon() ? common.lon_deg.start + 360.0 : common.lon_deg.last(), [&](std::size_t c) { return diff_colour(d, c); });
    cv.text(a.x0, a.y0 - 8, 9, d.name, kInk);
    colour_bar(cv, a.x1 + 8, a.y0 + 12, a.x1 + 18, a.y1, -d.range, d.range, "", diverging_colour);
  }
  cv.text(left, height - 14, 9, "grey: no data or no cloud in one of them", kInk);
  core::OutputGroup group;
  group.write(out, [&](std::FILE* f) { render::encode_png(f, width, height, cv.rgb()); });
  if (!render_out.empty()) {
    const auto t_render = std::chrono::steady_clock::now();
    int h3 = 0;
    const std::vector<std::string> caption = {
        "A " + std::filesystem::path(files[0]).filename().string() + " " + va.times[sa].iso_utc,
        "B " + std::filesystem::path(files[1]).filename().string() + " " + vb.times[sb].iso_utc,
        "common grid " + std::to_string(common.lon_deg.count) + "x" + std::to_string(common.lat_deg.count) + "x" +
            std::to_string(common.alt_m.count) + ", false colour: the hue only"};
    const std::vector<unsigned char> view = render_difference_view(cmp, va.times[sa], va.liquid_r_eff_um, render_w, render_h, caption, h3);
    std::size_t nodes[4] = {0, 0, 0, 0};
    for (core::Presence p : cmp.points) ++nodes[static_cast<int>(p)];
    std::printf("difference view: grid nodes with cloud in A only %zu (orange), B only %zu (blue), both %zu (white); rendered %dx%d in %.2f s\n",
                nodes[1], nodes[2], nodes[3], render_w, render_h,
                std::chrono::duration<double>(std::chrono::steady_clock::now() - t_render).count());
    group.write(render_out, [&](std::FILE* f) { render::encode_png(f, render_w, h3, view); });
  }
  if (!maps_out.empty()) {
    int mw = 0, mh = 0;
    const std::vector<unsigned char> maps = draped_maps(cmp, std::max(16, render_w / 2), std::max(16, render_h / 2), mw, mh);
    group.write(maps_out, [&](std::FILE* f) { render::encode_png(f, mw, mh, maps); });
  }
  if (!csv.empty()) {
    group.write(csv, [&](std::FILE* f) {
      put(f, "# A " + files[0] + " at " + va.times[sa].iso_utc + ", B " + files[1] + " at " + vb.times[sb].iso_utc + "; " + grid_line + "\n");
      put(f, "lon_deg,lat_deg,presence,cover_a,cover_b,d_cover,optical_depth_a,optical_depth_b,d_optical_depth,base_a_m,base_b_m,d_base_m,top_a_m,top_b_m,d_top_m\n");
      static const char* names[4] = {"neither", "a_only", "b_only", "both"};
      const core::Maps2D &ma = cmp.a.maps, &mb = cmp.b.maps;
      for (int j = 0; j < common.lat_deg.count; ++j)
        for (int i = 0; i < common.lon_deg.count; ++i) {
          const std::size_t c = common.column(i, j);
          put(f, num(common.lon_deg.at(i)) + "," + num(common.lat_deg.at(j)) + "," + names[static_cast<int>(cmp.columns[c])] + "," +
                     num(ma.cloud_cover[c]) + "," + num(mb.cloud_cover[c]) + "," + num(cmp.d_cover[c]) + "," + num(ma.optical_depth[c]) + "," +
                     num(mb.optical_depth[c]) + "," + num(cmp.d_optical_depth[c]) + "," + num(ma.cloud_base_m[c], "%.1f") + "," +
                     num(mb.cloud_base_m[c], "%.1f") + "," + num(cmp.d_base_m[c], "%.1f") + "," + num(ma.cloud_top_m[c], "%.1f") + "," +
                     num(mb.cloud_top_m[c], "%.1f") + "," + num(cmp.d_top_m[c], "%.1f") + "\n");
        }
    });
  }
  group.commit();
  std::printf("wrote %s%s%s%s%s%s%s\n", out.c_str(), csv.empty() ? "" : " and ", csv.c_str(), render_out.empty() ? "" : " and ",
              render_out.c_str(), maps_out.empty() ? "" : " and ", maps_out.c_str());
  return 0;
}

}  // namespace cv::cli
