// The cache of prepared time steps.
#include "kernel/volume_cache.hpp"

#include <algorithm>

namespace cv::core {

std::shared_ptr<const StepMedium> StepMediaCache::get(const std::string& source, CloudVolume& volume, std::size_t step, bool winds) {
  if (source != source_ || &volume != volume_) media_.clear(), source_ = source, volume_ = &volume;
  for (std::size_t i = 0; i < media_.size(); ++i) {
    if (media_[i]->step != step || (winds && !media_[i]->has_winds)) continue;
    std::shared_ptr<const StepMedium> m = media_[i];
    media_.erase(media_.begin() + static_cast<std::ptrdiff_t>(i));
    media_.push_back(m);
    return m;
  }
  auto m = std::make_shared<StepMedium>();
  m->step = step;
  const TimeStepData& data = volume.step(step);
  m->medium = grid_mean_extinction(volume.grid, data);
  if (winds) m->winds = step_winds(data), m->has_winds = true;
  for (std::size_t i = 0; i < media_.size(); ++i)
    if (media_[i]->step == step) {  // held without its winds: replaced
      media_.erase(media_.begin() + static_cast<std::ptrdiff_t>(i));
      break;
    }
  media_.push_back(m);
  if (media_.size() > 2) media_.erase(media_.begin());
  return m;
}

std::size_t StepMediaCache::bytes() const {
  std::size_t b = 0;
  for (const auto& m : media_) {
    for (const std::vector<float>* a : {&m->medium.liquid_per_m, &m->medium.ice_per_m, &m->medium.ground_m, &m->medium.fraction,
                                        &m->medium.lapse_k_per_km, &m->winds.u, &m->winds.v, &m->winds.w}) {
      b += a->size() * sizeof(float);
    }
    b += m->medium.detail_drift_cells.size() * sizeof(double);
  }
  return b;
}

std::shared_ptr<const PreparedVolume> PreparedVolumeCache::get(const std::string& source, CloudVolume& volume, const Instant& at,
                                                               TimeInterpolation mode, TimeInterpolationReport* report,
                                                               bool detail_drift) {
  if (!at.between()) {
    if (report) *report = TimeInterpolationReport{};
    return get(source, volume, at.step0, detail_drift);
  }
  const auto it = std::find_if(entries_.begin(), entries_.end(), [&](const Entry& e) {
    return e.source == source && e.step == at.step0 && e.step1 == at.step1 && e.fraction == at.fraction && e.mode == mode &&
           e.drift == detail_drift;
  });
  if (it != entries_.end()) {
    Entry e = *it;
    entries_.erase(it);
    entries_.push_back(e);
    if (report) *report = e.report, report->cost_ms = 0.0;
    return e.volume;
  }
  // The drift first: it may load earlier steps. Then each step's medium and winds taken before the
  // next step is loaded (which may evict it).
  std::vector<double> drift = detail_drift ? drift_.at(volume, at) : std::vector<double>{};
  const std::shared_ptr<const StepMedium> m0 = media_.get(source, volume, at.step0, true);
  const std::shared_ptr<const StepMedium> m1 = media_.get(source, volume, at.step1, true);
  const GridMeanExtinction& e0 = m0->medium;
  const StepWinds& w0 = m0->winds;
  const GridMeanExtinction& e1 = m1->medium;
  const StepWinds& w1 = m1->winds;
  Entry e;
  e.source = source, e.step = at.step0, e.step1 = at.step1, e.fraction = at.fraction, e.mode = mode, e.drift = detail_drift;
  GridMeanExtinction mixed = interpolate_extinction(volume.grid, e0, e1, w0, w1, at.gap_s, at.fraction, mode, &e.report);
  mixed.detail_drift_cells = std::move(drift);
  PreparedVolume prepared = prepare_volume(volume.grid, std::move(mixed), detail_drift);
  if (at.step0 < volume.times.size()) prepared.time_s = double(volume.times[at.step0].unix_s) + at.fraction * at.gap_s;
  if (e.report.used == TimeInterpolation::Advected) prepared.flow = angular_flow(volume.grid, w0, w1, at.fraction);
  e.volume = std::make_shared<const PreparedVolume>(std::move(prepared));
  ++prepared_;
  entries_.push_back(e);
  if (entries_.size() > kResident) entries_.erase(entries_.begin());
  if (report) *report = e.report;
  return e.volume;
}

std::shared_ptr<const PreparedVolume> PreparedVolumeCache::get(const std::string& source, CloudVolume& volume, std::size_t step,
                                                               bool detail_drift) {
  const auto it = std::find_if(entries_.begin(), entries_.end(), [&](const Entry& e) {
    return e.source == source && e.step == step && e.step1 == step && e.drift == detail_drift;
  });
  if (it != entries_.end()) {
    Entry e = *it;
    entries_.erase(it);
    entries_.push_back(e);
    return e.volume;
  }
  std::vector<double> drift;
  if (detail_drift) {  // before the step is taken: the drift may load earlier steps
    Instant at;
    at.step0 = at.step1 = step;
    drift = drift_.at(volume, at);
  }
  GridMeanExtinction medium = grid_mean_extinction(volume.grid, volume.step(step));
  medium.detail_drift_cells = std::move(drift);
  PreparedVolume prepared = prepare_volume(volume.grid, std::move(medium), detail_drift);
  if (step < volume.times.size()) prepared.time_s = double(volume.times[step].unix_s);
  auto v = std::make_shared<const PreparedVolume>(std::move(prepared));
  ++prepared_;
  Entry e;
  e.source = source, e.step = e.step1 = step, e.drift = detail_drift, e.volume = v;
  entries_.push_back(e);
  if (entries_.size() > kResident) entries_.erase(entries_.begin());
  return v;
}

}  // namespace cv::core
