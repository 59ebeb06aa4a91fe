// Speed of the photometric front end at 640x512 (issue 7): pyramid, selection, residuals, tracking,
// candidate search. Inputs: the test scene rendered once (two views 8 cm apart).
#include <benchmark/benchmark.h>

#include <memory>

#include "framework/photometric/synthetic_scene.h"
#include "framework/photometric/test_camera.h"
#include "rsvio/frontend/candidate_points.h"
#include "rsvio/frontend/frame_tracker.h"
#include "rsvio/photometric/pixel_selector.h"
#include "rsvio/photometric/point_observation.h"

namespace rsvio {
namespace {

Vec6 twist(double tx, double ty, double tz, double rx, double ry, double rz) {
  Vec6 v;
  v << tx, ty, tz, rx, ry, rz;
  return v;
}

struct Inputs {
  test::PinholeK K{500, 500, 319.5, 255.5, 640, 512};
  test::SyntheticScene scene{7};
  test::TestPinholeCamera camera{K};
  SE3d T_kf, T_new;
  cv::Mat kf_img, new_img, depth;
  std::shared_ptr<ImagePyramid> kf_pyr, new_pyr;
  std::vector<SelectedPixel> selected;
  std::vector<Vec2> uv;
  std::vector<double> idepth;

  Inputs() {
    T_new = SE3d::exp(twist(0.05, -0.02, 0.06, 0.01, -0.015, 0.005)) * T_kf;
    kf_img = scene.render(K, [&](double) { return test::toPoseCW(T_kf); }, &depth, 2);
    new_img = scene.render(K, [&](double) { return test::toPoseCW(T_new); }, nullptr, 2);
    kf_pyr = std::make_shared<ImagePyramid>(kf_img, 5);
    new_pyr = std::make_shared<ImagePyramid>(new_img, 5);
    PixelSelectorOptions so;
    so.num_points = 2000;
    selected = PixelSelector(so).select(*kf_pyr);
    for (const SelectedPixel& p : selected) {
      const double z = depth.at<float>(p.v, p.u);
      if (!(z > 0)) continue;
      uv.emplace_back(p.u, p.v);
      idepth.push_back(1.0 / (z * Vec3((p.u - K.cx) / K.fx, (p.v - K.cy) / K.fy, 1).norm()));
    }
  }
  TrackingReference reference() const {
    TrackingReference r;
    r.T_c_w = T_kf;
    r.pyramid = kf_pyr;
    for (size_t i = 0; i < uv.size(); ++i) r.points.push_back({uv[i], idepth[i], 1.0});
    return r;
  }
};

const Inputs& inputs() {
  static const Inputs in;
  return in;
}

void BM_Pyramid640x512(benchmark::State& state) {
  const Inputs& in = inputs();
  for (auto _ : state) {
    ImagePyramid p(in.new_img, 5);
    benchmark::DoNotOptimize(p.level(4).data());
  }
}
BENCHMARK(BM_Pyramid640x512)->Unit(benchmark::kMillisecond);

void BM_PixelSelection2000(benchmark::State& state) {
  const Inputs& in = inputs();
  PixelSelectorOptions o;
  o.num_points = 2000;
  const PixelSelector sel(o);
  size_t n = 0;
  for (auto _ : state) n = sel.select(*in.kf_pyr).size();
  state.counters["points"] = static_cast<double>(n);
}
BENCHMARK(BM_PixelSelection2000)->Unit(benchmark::kMillisecond);

void BM_ResidualEvaluation2000(benchmark::State& state) {
  const Inputs& in = inputs();
  const bool jacobians = state.range(0) != 0;
  const ResidualOptions ro;
  const std::vector<HostPoint> pts = makeHostPoints(in.camera, in.kf_pyr->level(0), in.uv, in.idepth, ro);
  ObservationFrames fr;
  fr.host.T_c_w0 = in.T_kf;
  fr.target.T_c_w0 = in.T_new;
  const RowTiming timing = RowTiming::global(in.K.height * 0.5 - 0.5);
  std::vector<Observation> out;
  double sum = 0;
  for (auto _ : state) {
    evaluateObservations(in.camera, timing, fr, in.new_pyr->level(0), pts, ro, out);
    if (jacobians)
      for (size_t i = 0; i < pts.size(); ++i)
        if (out[i].valid) sum += observationJacobians(out[i], pts[i], fr).d_r_d_idepth(0);
    benchmark::DoNotOptimize(sum);
  }
  state.counters["points"] = static_cast<double>(pts.size());
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * pts.size() * kPatternSize));
}
BENCHMARK(BM_ResidualEvaluation2000)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

void BM_TrackingResidualPassLevel0(benchmark::State& state) {
  const Inputs& in = inputs();
  TrackerOptions o;
  o.threads = static_cast<int>(state.range(0));
  FrameTracker t(o, in.camera, RowTiming::global(in.K.height * 0.5 - 0.5));
  t.setReference(in.reference());
  for (auto _ : state) {
    const FrameTracker::LevelEnergy e = t.levelEnergy(*in.new_pyr, TrackingFrame(), 0, in.T_new, AffineBrightness());
    benchmark::DoNotOptimize(e.energy);
  }
  state.counters["points"] = t.numReferencePoints(0);
}
BENCHMARK(BM_TrackingResidualPassLevel0)->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond);

void BM_TrackFrame(benchmark::State& state) {
  const Inputs& in = inputs();
  TrackerOptions o;
  o.threads = static_cast<int>(state.range(0));
  const bool rolling = state.range(1) != 0;
  const RowTiming timing = rolling ? RowTiming::rolling(in.K.height * 0.5 - 0.5, 20e-6, true)
                                   : RowTiming::global(in.K.height * 0.5 - 0.5);
  FrameTracker t(o, in.camera, timing);
  t.setReference(in.reference());
  // A constant-velocity guess off by a few cm and ~1 degree, as between two frames at 20 Hz.
  const SE3d guess = SE3d::exp(twist(0.02, 0.01, -0.02, 0.01, 0.005, 0.0)) * in.T_new;
  TrackingFrame info;
  if (rolling) info.twist = twist(0.5, 0.1, 0.2, 0.2, 0.3, 0.1);
  int iterations = 0;
  for (auto _ : state) {
    const TrackResult r = t.track(*in.new_pyr, info, {guess});
    iterations = r.iterations;
    benchmark::DoNotOptimize(r.T_c_w);
  }
  state.counters["lm_iterations"] = iterations;
}
BENCHMARK(BM_TrackFrame)->Args({1, 0})->Args({2, 0})->Args({1, 1})->Unit(benchmark::kMillisecond);

void BM_SetReference(benchmark::State& state) {
  const Inputs& in = inputs();
  FrameTracker t(TrackerOptions(), in.camera, RowTiming::global(in.K.height * 0.5 - 0.5));
  const TrackingReference ref = in.reference();
  for (auto _ : state) t.setReference(ref);
}
BENCHMARK(BM_SetReference)->Unit(benchmark::kMillisecond);

void BM_CandidateTrace2000(benchmark::State& state) {
  const Inputs& in = inputs();
  const CandidateTracer tracer(CandidateOptions(), ResidualOptions(), in.camera,
                               RowTiming::global(in.K.height * 0.5 - 0.5));
  const std::vector<CandidatePoint> fresh = tracer.create(in.kf_pyr->level(0), in.uv);
  const CandidateFrame host{RsFrame{in.T_kf, Vec6::Zero()}, {}, std::nan("")};
  const CandidateFrame target{RsFrame{in.T_new, Vec6::Zero()}, {}, std::nan("")};
  TraceStats st;
  for (auto _ : state) {
    state.PauseTiming();
    std::vector<CandidatePoint> c = fresh;
    state.ResumeTiming();
    st = tracer.trace(c, host, target, in.new_pyr->level(0));
  }
  state.counters["good"] = st.good;
  state.counters["points"] = static_cast<double>(fresh.size());
}
BENCHMARK(BM_CandidateTrace2000)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace rsvio

BENCHMARK_MAIN();
