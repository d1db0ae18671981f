// The viewer's ImGui panels. Every widget edits a field of the shared Scene directly, so the scene
// file stores exactly what is on screen; the main loop resets the accumulation on any change. The
// march settings' widgets come from their rows (core/settings/march_settings.def).
#include "viewer/panels.hpp"

#include <imgui.h>
#include <imgui_stdlib.h>

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <string>
#include <type_traits>

#include <glm/glm.hpp>

#include "render/gl.hpp"
#include "viewer/camera_controller.hpp"
#include "scene/quality.hpp"
#include "scene/scene_json.hpp"
#include "scene/instant.hpp"

namespace cv::viewer {
namespace {
bool drag_double(const char* label, double* v, double speed, double lo, double hi, const char* fmt,
                 ImGuiSliderFlags flags = 0) {
  return ImGui::DragScalar(label, ImGuiDataType_Double, v, static_cast<float>(speed), &lo, &hi, fmt,
                           flags | ImGuiSliderFlags_AlwaysClamp);
}
bool slider_double(const char* label, double* v, double lo, double hi, const char* fmt, ImGuiSliderFlags flags = 0) {
  return ImGui::SliderScalar(label, ImGuiDataType_Double, v, &lo, &hi, fmt, flags | ImGuiSliderFlags_AlwaysClamp);
}

// The timeline: play/pause, step back and forward, loop, speed, frames per step, the interpolation,
// and a scrubber in hours with the file's steps marked under it.
void time_controls(ViewerState& s) {
  Playhead& p = s.play;
  const auto& times = s.volume.times;
  const auto follow = [&] { s.scene.time.valid_utc = core::format_iso_utc(p.shown()); };
  if (s.scene.time.valid_utc.empty()) p.t_s = double(times[static_cast<std::size_t>(s.scene.time_step)].unix_s);
  if (ImGui::Button(p.playing ? "pause" : "play")) {
    p.playing = !p.playing;
    follow();
  }
  ImGui::SameLine();
  if (ImGui::Button("<")) p.step(times, -1), follow();
  ImGui::SameLine();
  if (ImGui::Button(">")) p.step(times, +1), follow();
  ImGui::SameLine();
  ImGui::Checkbox("loop", &p.loop);
  float speed = static_cast<float>(p.speed_h_per_s);
  if (ImGui::SliderFloat("forecast h / s", &speed, 0.05f, 48.0f, "%.2f", ImGuiSliderFlags_Logarithmic)) p.speed_h_per_s = speed;
  if (ImGui::SliderInt("frames per step", &p.frames_per_step, 1, 64)) p.reset(times);
  int mode = static_cast<int>(s.scene.time.interpolation);
  if (ImGui::Combo("between steps", &mode, "auto\0nearest\0linear\0advected\0")) s.scene.time.interpolation = static_cast<core::TimeInterpolation>(mode);
  const float span_h = static_cast<float>((p.last_s - p.first_s) / 3600.0);
  float h = static_cast<float>((p.t_s - p.first_s) / 3600.0);
  if (ImGui::SliderFloat("hours", &h, 0.0f, span_h, "%.2f")) {
    p.t_s = p.first_s + double(h) * 3600.0;
    follow();
  }
  // The steps, as ticks under the scrubber's track.
  const ImVec2 a = ImGui::GetItemRectMin(), b = ImGui::GetItemRectMax();
  const float pad = ImGui::GetStyle().GrabMinSize * 0.5f + ImGui::GetStyle().FramePadding.x * 0.5f;
  const float x0 = a.x + pad, x1 = a.x + ImGui::CalcItemWidth() - pad;
  ImDrawList* dl = ImGui::GetWindowDrawList();
  for (const auto& v : times) {
    const float f = span_h > 0.0f ? static_cast<float>((double(v.unix_s) - p.first_s) / 3600.0) / span_h : 0.0f;
    const float x = x0 + f * (x1 - x0);
    dl->AddLine(ImVec2(x, b.y - 4.0f), ImVec2(x, b.y), IM_COL32(255, 220, 120, 255), 2.0f);
  }
}

void data_panel(ViewerState& s, const PanelContext& ctx) {
  if (!ImGui::CollapsingHeader("Data", ImGuiTreeNodeFlags_DefaultOpen)) return;
  const auto& g = s.volume.grid;
  ImGui::TextWrapped("file: %s", s.scene.data.path.c_str());
  ImGui::Text("grid: %d x %d x %d", g.lon_deg.count, g.lat_deg.count, g.alt_m.count);
  ImGui::Text("lon %.3f..%.3f, lat %.3f..%.3f deg", g.lon_deg.start, g.lon_deg.last(), g.lat_deg.start, g.lat_deg.last());
  ImGui::Text("alt %.0f..%.0f m, step %.0f m", g.alt_m.start, g.alt_m.last(), g.alt_m.step);
  std::string fields;
  for (int i = 0; i < core::kFieldCount; ++i) {
    if (s.volume.has_field[static_cast<std::size_t>(i)]) fields += std::string(fields.empty() ? "" : ", ") + core::field_name(static_cast<core::Field>(i));
  }
  ImGui::TextWrapped("fields: %s", fields.empty() ? "(none)" : fields.c_str());
  const int n = static_cast<int>(s.volume.times.size());
  if (n > 1 && ImGui::SliderInt("time step", &s.scene.time_step, 0, n - 1, "%d", ImGuiSliderFlags_AlwaysClamp)) {
    s.scene.time.valid_utc.clear();  // the slider picks a step: the instant follows it
  }
  if (n > 1 && s.timeline) time_controls(s);
  ImGui::TextWrapped("valid time: %s", ctx.instant_text.c_str());
  if (!ctx.time_warning.empty()) ImGui::TextColored(ImVec4(1.0f, 0.5f, 0.4f, 1.0f), "%s", ctx.time_warning.c_str());
  if (!ctx.sun_note.empty()) ImGui::TextWrapped("%s", ctx.sun_note.c_str());
  if (ImGui::TreeNode("import report")) {
    ImGui::BeginChild("report", ImVec2(0, 160), true, ImGuiWindowFlags_HorizontalScrollbar);
    ImGui::TextUnformatted(s.import_report.c_str());
    ImGui::EndChild();
    ImGui::TreePop();
  }
}

void camera_panel(ViewerState& s, PanelContext& ctx) {
  if (!ImGui::CollapsingHeader("Camera", ImGuiTreeNodeFlags_DefaultOpen)) return;
  core::Camera& c = *s.scene.camera;
  int mode = s.fly_mode ? 1 : 0;
  ImGui::RadioButton("orbit", &mode, 0);
  ImGui::SameLine();
  ImGui::RadioButton("fly", &mode, 1);
  s.fly_mode = mode == 1;
  ImGui::TextDisabled(s.fly_mode ? "drag: look; WASD move, QE down/up, shift x5 (%.0f m/s)"
                                 : "left drag: orbit; right drag: look; wheel: zoom (%.0f m/s fly)",
                      fly_speed_m_per_s(c.alt_m));
  drag_double("lat (deg)", &c.lat_deg, 0.01, -90.0, 90.0, "%.4f");
  drag_double("lon (deg)", &c.lon_deg, 0.01, -540.0, 540.0, "%.4f");
  drag_double("alt (m)", &c.alt_m, std::max(1.0, 0.005 * c.alt_m), 0.0, 4e8, "%.0f");
  drag_double("heading (deg)", &c.heading_deg, 0.2, -360.0, 360.0, "%.1f");
  drag_double("pitch (deg)", &c.pitch_deg, 0.2, -90.0, 90.0, "%.1f");
  slider_double("fov (deg)", &c.fov_deg, 5.0, 120.0, "%.0f");
  ImGui::InputDouble("go-to lat", &ctx.goto_lat_deg, 0.0, 0.0, "%.4f");
  ImGui::InputDouble("go-to lon", &ctx.goto_lon_deg, 0.0, 0.0, "%.4f");
  ImGui::InputDouble("go-to alt (m)", &ctx.goto_alt_m, 0.0, 0.0, "%.0f");
  if (ImGui::Button("go")) {
    c.lat_deg = std::clamp(ctx.goto_lat_deg, -90.0, 90.0);
    c.lon_deg = ctx.goto_lon_deg;
    c.alt_m = std::clamp(ctx.goto_alt_m, 0.0, 4e8);
  }
  ImGui::SameLine();
  if (ImGui::Button("reset view")) {
    c = ctx.home;
    s.fly_mode = false;
  }
}

void sun_panel(ViewerState& s, PanelContext& ctx) {
  if (!ImGui::CollapsingHeader("Sun & date/time")) return;
  int mode = static_cast<int>(s.scene.sun.mode);
  ImGui::Combo("sun from", &mode, "valid time\0date/time (UTC)\0subsolar point\0local noon (teaching)\0");
  s.scene.sun.mode = static_cast<core::SunMode>(mode);
  if (s.scene.sun.mode == core::SunMode::DateTime) ImGui::InputText("UTC", &s.scene.sun.datetime_utc);
  if (s.scene.sun.mode == core::SunMode::Manual) {
    slider_double("subsolar lat", &s.scene.sun.subsolar_lat_deg, -23.44, 23.44, "%.2f");
    slider_double("subsolar lon", &s.scene.sun.subsolar_lon_deg, -180.0, 180.0, "%.2f");
  }
  slider_double("irradiance", &s.scene.sun.irradiance, 0.0, 10.0, "%.2f");
  ImGui::Text("sun overhead at %.2f, %.2f", ctx.sun.subsolar_lat_deg, ctx.sun.subsolar_lon_deg);
  if (!ctx.sun_error.empty()) ImGui::TextColored(ImVec4(1.0f, 0.5f, 0.4f, 1.0f), "%s", ctx.sun_error.c_str());
  if (!ctx.sun_note.empty()) ImGui::TextWrapped("%s", ctx.sun_note.c_str());
}

// Whether a row's setting is on (a true bool, a non-zero number): rows that need it show only then.
bool setting_on(const core::MarchSettings& m, const char* key) {
  bool on = false;
  core::for_each_march_setting(m, [&](const core::SettingRow& row, const auto& value) {
    using T = std::decay_t<decltype(value)>;
    if constexpr (std::is_same_v<T, bool> || std::is_same_v<T, int> || std::is_same_v<T, double>) {
      if (std::string(row.key) == key) on = value != T{};
    }
  });
  return on;
}

// One widget per row of this group that has a label, with the row's widget range (the row's full
// range where usable; logarithmic where the row says so). The row's line of documentation is
// the tooltip.
void march_widgets(core::MarchSettings& m, core::SettingGroup group) {
  core::for_each_march_setting(m, [&](const core::SettingRow& row, auto& value) {
    using T = std::decay_t<decltype(value)>;
    if (row.group != group || !row.label || (row.needs && !setting_on(m, row.needs))) return;
    const ImGuiSliderFlags log = row.wlog ? ImGuiSliderFlags_Logarithmic : 0;
    if constexpr (std::is_same_v<T, bool>) {
      if (row.kind == core::SettingKind::Choice) {
        int choice = value ? 1 : 0;
        if (ImGui::Combo(row.label, &choice, row.choice_labels.data(), 2)) value = choice == 1;
      } else {
        ImGui::Checkbox(row.label, &value);
      }
    } else if constexpr (std::is_same_v<T, int>) {
      ImGui::SliderInt(row.label, &value, static_cast<int>(row.wlo), static_cast<int>(row.whi), "%d",
                       ImGuiSliderFlags_AlwaysClamp | log);
    } else if constexpr (std::is_same_v<T, double>) {
      slider_double(row.label, &value, row.wlo, row.whi, "%.5g", log);
    } else if constexpr (std::is_same_v<T, glm::dvec3>) {
      float rgb[3] = {static_cast<float>(value.x), static_cast<float>(value.y), static_cast<float>(value.z)};
      if (ImGui::ColorEdit3(row.label, rgb, ImGuiColorEditFlags_Float)) {
        value = glm::clamp(glm::dvec3(rgb[0], rgb[1], rgb[2]), row.lo, row.hi);
      }
    }
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s: %s", row.key, row.doc);
  });
}

void lighting_panel(ViewerState& s) {
  if (!ImGui::CollapsingHeader("Lighting")) return;
  march_widgets(s.scene.render.march, core::SettingGroup::Medium);
}

void features_panel(ViewerState& s) {
  if (!ImGui::CollapsingHeader("Features")) return;
  march_widgets(s.scene.render.march, core::SettingGroup::Features);
}

void quality_panel(ViewerState& s, const PanelContext& ctx) {
  if (!ImGui::CollapsingHeader("Quality")) return;
  // The GPU path tracer as a progressive mode: full multiple scattering, the sky and the ground,
  // one sample per pixel per frame, with the overlays and the haze in front of the clouds as the march has them.
  ImGui::Checkbox("path tracer (progressive reference)", &s.path_trace);
  if (s.path_trace) ImGui::SliderInt("path samples per pixel", &s.path_spp, 1, 65536, "%d", ImGuiSliderFlags_AlwaysClamp | ImGuiSliderFlags_Logarithmic);
  // Temporal reprojection: 1/16 of the pixels marched per frame, the rest carried from the last image.
  ImGui::Checkbox("reprojection (1/16 of the pixels per frame)", &s.reproject);
  march_widgets(s.scene.render.march, core::SettingGroup::Quality);
  core::RenderSettings& r = s.scene.render;
  slider_double("resolution scale", &r.resolution_scale, 0.1, 1.0, "%.2f");
  ImGui::SliderInt("accumulate (frames)", &r.accumulate, 1, 1024, "%d", ImGuiSliderFlags_AlwaysClamp | ImGuiSliderFlags_Logarithmic);
  if (ImGui::Checkbox("automatic exposure", &r.auto_exposure) && !r.auto_exposure) r.exposure = ctx.auto_exposure;
  if (r.auto_exposure) {
    if (ctx.exposure_held) {
      ImGui::Text("exposure %.3g, held while playing (the brightest frame played)", ctx.auto_exposure);
    } else {
      ImGui::Text("exposure %.3g (the 99th percentile of lit pixels at 0.8)", ctx.auto_exposure);
    }
  } else {
    slider_double("exposure", &r.exposure, 1e-3, 1e4, "%.3g", ImGuiSliderFlags_Logarithmic);
  }
  // 0 is off; on, the budget sets the step, sun steps, octaves, adaptive and scale above.
  drag_double("frame budget (ms)", &r.budget_ms, 1.0, 0.0, 1e7, r.budget_ms > 0.0 ? "%.0f" : "off");
  if (r.budget_ms > 0.0 && !ctx.budget_text.empty()) ImGui::TextWrapped("budget: %s", ctx.budget_text.c_str());
}

void overlay_panel(ViewerState& s, const FrameStats& stats) {
  if (!ImGui::CollapsingHeader("Overlays")) return;
  // Each overlay: on/off, its parameters from the overlay table, and what it costs.
  std::size_t remove = s.scene.overlays.size();
  for (std::size_t i = 0; i < s.scene.overlays.size(); ++i) {
    core::OverlaySpec& o = s.scene.overlays[i];
    ImGui::PushID(static_cast<int>(i));
    ImGui::Checkbox(o.type.c_str(), &o.enabled);
    ImGui::SameLine();
    if (ImGui::SmallButton("remove")) remove = i;
    if (i < stats.overlays.size()) {
      ImGui::SameLine();
      ImGui::TextDisabled("build %.1f ms, draw %.2f ms", stats.overlays[i].build_ms, stats.overlays[i].draw_ms);
    }
    for (const core::OverlayParamRow& row : core::overlay_param_rows()) {
      if (o.type != row.overlay) continue;
      if (row.kind == core::OverlayParamKind::Number) {
        double v = o.number(row.key);
        const double lo = std::max(row.lo, -1e6), hi = std::min(row.hi, 1e6);
        if (drag_double(row.key, &v, std::max(1e-3, 0.01 * std::abs(v)), lo, hi, "%.4g")) o.numbers[row.key] = std::clamp(v, row.lo, row.hi);
      } else if (row.kind == core::OverlayParamKind::Rgb) {
        const glm::dvec3 c = o.color(row.key);
        float f[3] = {static_cast<float>(c.x), static_cast<float>(c.y), static_cast<float>(c.z)};
        if (ImGui::ColorEdit3(row.key, f, ImGuiColorEditFlags_Float | ImGuiColorEditFlags_HDR)) {
          o.colors[row.key] = glm::clamp(glm::dvec3(f[0], f[1], f[2]), row.lo, row.hi);
        }
      } else {
        ImGui::Text("%s: %s", row.key, o.text(row.key).c_str());
      }
    }
    ImGui::PopID();
  }
  if (remove < s.scene.overlays.size()) s.scene.overlays.erase(s.scene.overlays.begin() + static_cast<std::ptrdiff_t>(remove));
  for (const std::string& type : core::overlay_types()) {
    if (type == "isosurface") continue;  // needs a field and a value: from a scene file or --overlay
    if (ImGui::SmallButton(("add " + type).c_str())) s.scene.overlays.push_back(core::default_overlay(type));
    ImGui::SameLine();
  }
  ImGui::NewLine();
}

// The camera path (issue 16): keyframes at the current view and time, their order and path times,
// the preview, and the record command. The path is saved and loaded with the scene file.
void path_panel(ViewerState& s, PanelContext& ctx) {
  if (!ImGui::CollapsingHeader("Camera path")) return;
  KeyframeEditor& ed = s.keys;
  if (ImGui::Button("add keyframe here")) {
    const core::Camera cam = s.scene.camera ? *s.scene.camera : ctx.home;
    std::string utc = s.scene.time.valid_utc;
    if (utc.empty() && core::times_known(s.volume.times)) utc = s.volume.times[static_cast<std::size_t>(s.scene.time_step)].iso_utc;
    add_keyframe(s.scene, ed, cam, utc);
  }
  ImGui::SameLine();
  if (ImGui::Button("delete")) delete_keyframe(s.scene, ed);
  ImGui::SameLine();
  if (ImGui::ArrowButton("earlier", ImGuiDir_Up)) move_keyframe(s.scene, ed, -1);
  ImGui::SameLine();
  if (ImGui::ArrowButton("later", ImGuiDir_Down)) move_keyframe(s.scene, ed, +1);
  if (s.scene.path) {
    for (std::size_t i = 0; i < s.scene.path->keyframes.size(); ++i) {
      const core::PathKeyframe& k = s.scene.path->keyframes[i];
      char label[200];
      std::snprintf(label, sizeof label, "%zu: %.2f s  %.2f, %.2f  %.0f m  %s", i, k.t_s, k.lat_deg, k.lon_deg, k.alt_m,
                    k.valid_utc.empty() ? "" : k.valid_utc.c_str());
      if (ImGui::Selectable(label, ed.selected == static_cast<int>(i))) ed.selected = static_cast<int>(i);
    }
    if (ed.selected >= 0 && ed.selected < static_cast<int>(s.scene.path->keyframes.size())) {
      double t = s.scene.path->keyframes[static_cast<std::size_t>(ed.selected)].t_s;
      if (ImGui::InputDouble("path time (s)", &t, 0.5, 2.0, "%.2f", ImGuiInputTextFlags_EnterReturnsTrue)) set_keyframe_time(s.scene, ed, t);
      if (ImGui::Button("go to keyframe")) {
        const core::PathKeyframe& k = s.scene.path->keyframes[static_cast<std::size_t>(ed.selected)];
        core::Camera c = s.scene.camera ? *s.scene.camera : ctx.home;
        c.lat_deg = k.lat_deg, c.lon_deg = k.lon_deg, c.alt_m = k.alt_m, c.heading_deg = k.heading_deg, c.pitch_deg = k.pitch_deg,
        c.fov_deg = k.fov_deg;
        s.scene.camera = c;
        if (!k.valid_utc.empty()) s.scene.time.valid_utc = k.valid_utc;
      }
    }
    bool constant = s.scene.path->speed == core::PathSpeed::Constant;
    if (ImGui::Checkbox("constant speed", &constant)) s.scene.path->speed = constant ? core::PathSpeed::Constant : core::PathSpeed::Keyframes;
    ImGui::SameLine();
    ImGui::Checkbox("ease in/out", &s.scene.path->ease);
    drag_double("weather h per s (0: keyframes' times)", &s.scene.path->weather_hours_per_s, 0.01, 0.0, 1000.0, "%.3f");
  }
  const std::string problem = path_problem(s.scene);
  if (problem.empty()) {
    ImGui::Checkbox("preview", &ed.previewing);
    ImGui::SameLine();
    ImGui::Checkbox("draw the path", &ed.draw_path);
    if (ed.previewing) ImGui::Text("path time %.2f s", ed.preview_t_s);
    ImGui::TextWrapped("save the scene file, then: %s", record_command(ctx.scene_path, s.scene).c_str());
  } else {
    ed.previewing = false;
    ImGui::TextDisabled("%s", problem.c_str());
  }
  if (!ed.message.empty()) ImGui::TextWrapped("%s", ed.message.c_str());
}

// Several views (issue 17): the views open with their source and valid time, the layout (a grid, or
// a swipe divider between two views), the link of cameras and time, and a view to add.
void views_panel(ViewerState& s) {
  if (!ImGui::CollapsingHeader("Views")) return;
  ViewsPanel& v = s.views;
  const int n = static_cast<int>(v.labels.size());
  for (int i = 0; i < n; ++i) {
    ImGui::PushID(i);
    if (ImGui::SmallButton("<")) v.step_view = i, v.step_dir = -1;
    ImGui::SameLine();
    if (ImGui::SmallButton(">")) v.step_view = i, v.step_dir = +1;
    ImGui::SameLine();
    if (i > 0 && ImGui::SmallButton("close")) v.remove_requested = i;
    if (i > 0) ImGui::SameLine();
    ImGui::TextWrapped("%d: %s", i, v.labels[static_cast<std::size_t>(i)].c_str());
    ImGui::PopID();
  }
  int layout = v.layout == ViewLayout::Swipe ? 1 : 0;
  if (ImGui::Combo("layout", &layout, "grid\0swipe (two views)\0")) {
    if (layout == 1 && n != 2) v.message = "a swipe divider splits two views; " + std::to_string(n) + " are open";
    else v.layout = layout == 1 ? ViewLayout::Swipe : ViewLayout::Grid, v.message.clear();
  }
  if (v.layout == ViewLayout::Swipe) slider_double("divider", &v.divider, 0.0, 1.0, "%.2f");
  ImGui::Checkbox("link cameras", &v.link_camera);
  ImGui::SameLine();
  ImGui::Checkbox("link time", &v.link_time);
  if (n < kMaxViews) {
    ImGui::InputText("source", &v.add_source);
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("FILE, FILE@TIME (a step or a UTC time), or @TIME: this file at another time");
    ImGui::SameLine();
    if (ImGui::Button("add view")) v.add_requested = true;
  }
  if (!v.message.empty()) ImGui::TextWrapped("%s", v.message.c_str());
}

// The probe (a click on a pixel): the column there per level, its summary, and a CSV of it, as
// `cloudviewer probe --csv` writes it.
void probe_window(ProbePanel& p) {
  if (!p.open) return;
  ImGui::SetNextWindowSize(ImVec2(520, 360), ImGuiCond_FirstUseEver);
  if (!ImGui::Begin("Probe", &p.open)) {
    ImGui::End();
    return;
  }
  if (!p.source.empty()) {
    const core::ColumnProbe& c = p.column;
    ImGui::TextWrapped("view %d: %s, step %zu (%s), lat %.4f, lon %.4f; ground %s", p.view, p.source.c_str(), p.step, p.valid.c_str(),
                       p.lat_deg, p.lon_deg, std::isfinite(c.ground_m) ? (std::to_string(std::lround(c.ground_m)) + " m").c_str() : "unknown");
    char base[32] = "none", top[32] = "none";
    if (std::isfinite(c.base_m)) std::snprintf(base, sizeof base, "%.0f m", c.base_m);
    if (std::isfinite(c.top_m)) std::snprintf(top, sizeof top, "%.0f m", c.top_m);
    ImGui::Text("cover %.3f, base %s, top %s, optical depth %.4g", c.cover, base, top, c.optical_depth);
    if (p.ray) {  // where the light came from along the clicked pixel's ray
      char first[32] = "none", half[32] = "never";
      if (p.ray->first_cloud_m >= 0) std::snprintf(first, sizeof first, "%.2f km", p.ray->first_cloud_m / 1000.0);
      if (p.ray->half_transmittance_m >= 0) std::snprintf(half, sizeof half, "%.2f km", p.ray->half_transmittance_m / 1000.0);
      ImGui::Text("view ray (%.1f km to the ground): first cloud %s, transmittance 0.5 at %s, ray transmittance %.3g",
                  p.ray->distance_to_target_m / 1000.0, first, half, p.ray->transmittance);
    }
    ImGui::InputText("CSV", &p.csv_path);
    ImGui::SameLine();
    if (ImGui::Button("save")) save_probe_csv(p);
    const ImGuiTableFlags flags = ImGuiTableFlags_Borders | ImGuiTableFlags_RowBg | ImGuiTableFlags_ScrollY | ImGuiTableFlags_SizingFixedFit;
    if (ImGui::BeginTable("levels", 8, flags, ImVec2(0, 0))) {
      ImGui::TableSetupScrollFreeze(0, 1);
      for (const char* h : {"alt (m)", "p (hPa)", "cloud fraction", "ext liquid (1/m)", "ext ice (1/m)", "T (K)", "u (m/s)", "v (m/s)"}) {
        ImGui::TableSetupColumn(h);
      }
      ImGui::TableHeadersRow();
      for (auto it = c.levels.rbegin(); it != c.levels.rend(); ++it) {  // top first, as a sounding reads
        ImGui::TableNextRow();
        const double v[] = {it->alt_m, it->pressure_pa / 100.0, it->cloud_fraction, it->ext_liquid_per_m, it->ext_ice_per_m, it->temperature_k,
                            it->wind_u_m_s, it->wind_v_m_s};
        const bool shown[] = {true, p.has_pressure, true, true, true, p.has_temperature, p.has_wind, p.has_wind};
        const char* fmt[] = {"%.0f", "%.1f", "%.3f", "%.3g", "%.3g", "%.1f", "%.1f", "%.1f"};
        for (int k = 0; k < 8; ++k) {
          ImGui::TableSetColumnIndex(k);
          if (shown[k] && std::isfinite(v[k])) ImGui::Text(fmt[k], v[k]);
          else ImGui::TextDisabled("-");
        }
      }
      ImGui::EndTable();
    }
  }
  if (!p.message.empty()) ImGui::TextWrapped("%s", p.message.c_str());
  ImGui::End();
}

// A figure's canvas as an RGB8 texture, uploaded again when its version changed.
void upload_figure(unsigned& texture, int& shown_version, int version, const plots::Canvas& canvas) {
  if (texture != 0 && shown_version == version) return;
  if (texture == 0) {
    GLuint t = 0;
    glGenTextures(1, &t);
    texture = t;
  }
  glBindTexture(GL_TEXTURE_2D, texture);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB8, canvas.width(), canvas.height(), 0, GL_RGB, GL_UNSIGNED_BYTE, canvas.rgb().data());
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
  glBindTexture(GL_TEXTURE_2D, 0);
  shown_version = version;
}

// Shows a figure at the window's width (at most its own size); returns its top left on screen and
// the scale from the figure's pixels.
ImVec2 show_figure(unsigned texture, const plots::Canvas& canvas, float& scale) {
  const float avail = ImGui::GetContentRegionAvail().x;
  scale = std::min(1.0f, std::max(0.1f, avail / static_cast<float>(canvas.width())));
  const ImVec2 at = ImGui::GetCursorScreenPos();
  ImGui::Image(reinterpret_cast<ImTextureID>(static_cast<std::uintptr_t>(texture)),
               ImVec2(canvas.width() * scale, canvas.height() * scale));
  return at;
}

// A line in the disabled colour, wrapped at the window's edge.
void note(const char* fmt, ...) IM_FMTARGS(1);
void note(const char* fmt, ...) {
  ImGui::PushStyleColor(ImGuiCol_Text, ImGui::GetStyle().Colors[ImGuiCol_TextDisabled]);
  va_list args;
  va_start(args, fmt);
  ImGui::TextWrappedV(fmt, args);
  va_end(args);
  ImGui::PopStyleColor();
}

void message_line(const std::string& m) {
  if (!m.empty()) ImGui::TextWrapped("%s", m.c_str());
}

// The vertical section (plot_panels.hpp): two ends typed or taken from the last probe click, a
// field, the figure `cloudviewer section` draws, and save.
void section_window(ViewerState& s, PanelContext& ctx) {
  SectionPanel& p = s.section;
  if (!p.open) return;
  ImGui::SetNextWindowPos(ImVec2(356, 8), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSize(ImVec2(620, 500), ImGuiCond_FirstUseEver);
  if (!ImGui::Begin("Section", &p.open)) {
    ImGui::End();
    return;
  }
  plots::SectionInputs& in = p.inputs;
  double from[2] = {in.lat1, in.lon1}, to[2] = {in.lat2, in.lon2};
  if (ImGui::InputScalarN("from lat, lon", ImGuiDataType_Double, from, 2, nullptr, nullptr, "%.4f")) in.lat1 = from[0], in.lon1 = from[1];
  ImGui::SameLine();
  if (ImGui::Button("probe##from")) take_probe_point(p, s.probe, 0);
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("the point of the last probe click");
  if (ImGui::InputScalarN("to lat, lon", ImGuiDataType_Double, to, 2, nullptr, nullptr, "%.4f")) in.lat2 = to[0], in.lon2 = to[1];
  ImGui::SameLine();
  if (ImGui::Button("probe##to")) take_probe_point(p, s.probe, 1);
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("the point of the last probe click");
  ImGui::InputText("field", &in.field);
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("extinction (what the march samples) or a 3-D field the file holds, as section --field");
  ImGui::SameLine();
  if (ImGui::Button("draw")) p.requested = true;
  if (p.has_figure) {
    note("%s, step %zu (%s); brown: ground, black: cloud boundary, grey: no data", p.source.c_str(), p.step,
                        p.valid.c_str());
    upload_figure(ctx.section_texture, ctx.section_version, p.version, p.figure.canvas);
    float scale = 1.0f;
    show_figure(ctx.section_texture, p.figure.canvas, scale);
    ImGui::InputText("PNG", &p.png_path);
    ImGui::InputText("CSV", &p.csv_path);
    ImGui::SameLine();
    if (ImGui::Button("save")) save_section(p);
  }
  message_line(p.message);
  ImGui::End();
}

// The time series at a point (plot_panels.hpp): cover, optical depth, base and top at each of the
// file's steps, as `cloudviewer series` draws them, with a marker at view 0's time, and save.
void series_window(ViewerState& s, PanelContext& ctx) {
  SeriesPanel& p = s.series;
  if (!p.open) return;
  ImGui::SetNextWindowPos(ImVec2(660, 200), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSize(ImVec2(600, 500), ImGuiCond_FirstUseEver);
  if (!ImGui::Begin("Series", &p.open)) {
    ImGui::End();
    return;
  }
  double at[2] = {p.lat_deg, p.lon_deg};
  if (ImGui::InputScalarN("at lat, lon", ImGuiDataType_Double, at, 2, nullptr, nullptr, "%.4f")) p.lat_deg = at[0], p.lon_deg = at[1];
  ImGui::SameLine();
  if (ImGui::Button("probe")) take_probe_point(p, s.probe);
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("the point of the last probe click");
  ImGui::SameLine();
  if (ImGui::Button("draw")) p.requested = true;
  if (p.has_figure) {
    note("%s at lat %.4f, lon %.4f, %zu steps; blue: base, red: top; the line: the time shown", p.source.c_str(),
                        p.at_lat, p.at_lon, p.figure.columns.size());
    upload_figure(ctx.series_texture, ctx.series_version, p.version, p.figure.canvas);
    float scale = 1.0f;
    const ImVec2 o = show_figure(ctx.series_texture, p.figure.canvas, scale);
    const double x = series_marker_x(p, s.series_now_hours);
    if (std::isfinite(x)) {
      ImGui::GetWindowDrawList()->AddLine(ImVec2(o.x + static_cast<float>(x) * scale, o.y + p.figure.top * scale),
                                          ImVec2(o.x + static_cast<float>(x) * scale, o.y + p.figure.bottom * scale),
                                          IM_COL32(230, 140, 0, 255), 2.0f);
    }
    ImGui::InputText("PNG", &p.png_path);
    ImGui::InputText("CSV", &p.csv_path);
    ImGui::SameLine();
    if (ImGui::Button("save")) save_series(p);
  }
  message_line(p.message);
  ImGui::End();
}

void scene_panel(ViewerState& s, PanelContext& ctx) {
  if (!ImGui::CollapsingHeader("Scene file")) return;
  ImGui::InputText("path", &ctx.scene_path);
  if (ImGui::Button("save")) {
    try {
      core::save_scene(scene_to_save(s), ctx.scene_path);
      ctx.scene_message = "saved " + ctx.scene_path;
    } catch (const std::exception& e) {
      ctx.scene_message = e.what();
    }
  }
  ImGui::SameLine();
  if (ImGui::Button("load")) {
    // Camera, sun, time and settings come from the file; its data must be the data on screen
    // (another file means another volume: start the viewer on that scene instead).
    try {
      core::Scene loaded = core::load_scene(ctx.scene_path);
      if (loaded.data.path != s.scene.data.path) {
        ctx.scene_message = ctx.scene_path + ": data.path is " + loaded.data.path + ", not the data on screen (" +
                            s.scene.data.path + "): run cloudviewer view " + ctx.scene_path;
      } else {
        const int w = s.scene.width, h = s.scene.height;
        s.scene = loaded;
        s.scene.width = w, s.scene.height = h;  // the window keeps its size
        if (s.scene.render.march.quality.view_step_m <= 0.0) {
          s.scene.render.march.quality.view_step_m = core::resolve_view_step_m(s.scene.render, s.volume.grid);
        }
        ctx.scene_message = "loaded " + ctx.scene_path;
      }
    } catch (const std::exception& e) {
      ctx.scene_message = e.what();
    }
  }
  if (!ctx.scene_message.empty()) ImGui::TextWrapped("%s", ctx.scene_message.c_str());
}
}  // namespace

void draw_panels(ViewerState& state, PanelContext& ctx, const FrameStats& stats) {
  ImGui::SetNextWindowPos(ImVec2(8, 8), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSize(ImVec2(340, 520), ImGuiCond_FirstUseEver);
  if (ImGui::Begin("cloudviewer")) {
    data_panel(state, ctx);
    camera_panel(state, ctx);
    sun_panel(state, ctx);
    lighting_panel(state);
    features_panel(state);
    quality_panel(state, ctx);
    overlay_panel(state, stats);
    path_panel(state, ctx);
    views_panel(state);
    scene_panel(state, ctx);
    if (ImGui::Button("section")) state.section.open = !state.section.open;
    ImGui::SameLine();
    if (ImGui::Button("series")) state.series.open = !state.series.open;
    ImGui::TextDisabled("F1 hides the panels; a click (no drag) on the globe probes the column; %s", stats.renderer.c_str());
  }
  ImGui::End();
  probe_window(state.probe);
  section_window(state, ctx);
  series_window(state, ctx);
}

void release_panel_textures(PanelContext& ctx) {
  for (unsigned* t : {&ctx.section_texture, &ctx.series_texture}) {
    if (*t != 0) {
      const GLuint id = *t;
      glDeleteTextures(1, &id);
      *t = 0;
    }
  }
}

void draw_stats_overlay(const FrameStats& s, int target) {
  const ImGuiViewport* vp = ImGui::GetMainViewport();
  ImGui::SetNextWindowPos(ImVec2(vp->WorkPos.x + vp->WorkSize.x - 8, vp->WorkPos.y + 8), ImGuiCond_Always, ImVec2(1, 0));
  ImGui::SetNextWindowBgAlpha(0.5f);
  const ImGuiWindowFlags flags = ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_AlwaysAutoResize | ImGuiWindowFlags_NoSavedSettings |
                                 ImGuiWindowFlags_NoFocusOnAppearing | ImGuiWindowFlags_NoNav | ImGuiWindowFlags_NoMove;
  if (ImGui::Begin("statistics", nullptr, flags)) {
    ImGui::Text("%s %.2f ms, accumulate + draw %.2f ms", s.path_trace ? "path trace" : "march", s.march_ms, s.present_ms);
    if (s.path_trace) {
      ImGui::Text("path tracer: %d / %d samples per pixel at %d x %d", s.accumulated, target, s.march_w, s.march_h);
      if (s.accumulated >= 2) ImGui::Text("mean relative standard error %.4f", s.path_error);
      ImGui::Text("%.1f FPS", s.fps);
      ImGui::End();
      return;
    }
    if (s.reprojecting) {
      ImGui::Text("reprojection: %d / 16 frames since the last change at %d x %d", std::min(s.accumulated, 16), s.march_w, s.march_h);
    } else {
      ImGui::Text("frames %d / %d at %d x %d", s.accumulated, target, s.march_w, s.march_h);
    }
    ImGui::Text("%.1f FPS", s.fps);
    const core::MarchStats& m = s.march;
    ImGui::Text("view samples %llu, skipped %llu (%llu jumps)", static_cast<unsigned long long>(m.view_samples),
                static_cast<unsigned long long>(m.view_skipped), static_cast<unsigned long long>(m.bricks_jumped));
    ImGui::Text("sun samples %llu, skipped or cut off %llu", static_cast<unsigned long long>(m.sun_samples),
                static_cast<unsigned long long>(m.sun_skipped));
    ImGui::Text("rays missing the cloud layer %llu", static_cast<unsigned long long>(m.rays_missed));
    ImGui::Text("octave terms %llu of %llu (the gate left out the rest)", static_cast<unsigned long long>(m.octave_terms),
                static_cast<unsigned long long>(m.octave_terms_full));
    if (m.sun_down) ImGui::Text("night over the whole cloud layer: sun marches left out");
    if (!s.prefetch.empty()) ImGui::Text("%s", s.prefetch.c_str());
  }
  ImGui::End();
}

}  // namespace cv::viewer
