// Speed of the specular-path solver: one glint (reflection) and one
// refracted pupil-border point, for spheres, conicoids and two-surface
// corneas, in the remote-tracker geometry of the reference cases (eye at
// 600 mm, yaw 15 degrees, LEDs 120 mm beside the camera).

#include <benchmark/benchmark.h>

#include <cmath>

#include "purkinje/models/specular.h"

namespace purkinje {
namespace {

Eye bench_eye(double asphericity, bool two_surfaces) {
  EyeModel m;
  m.anterior_cornea = {7.8, asphericity};
  m.limbus_radius_mm = 5.9;
  m.iris_depth_mm = 3.6;
  m.pupil_radius_mm = 2.5;
  if (two_surfaces) {
    m.posterior_cornea = PosteriorCornea{{6.5, 0.0}, 0.55, 1.376};
    m.aqueous_index = 1.336;
  }
  return Eye::with_cornea_center(m, {0, 0, 600}, optical_axis_from_yaw_pitch(0.26, 0.05));
}

void glint(benchmark::State& state, double q) {
  const Eye eye = bench_eye(q, false);
  int i = 0;
  for (auto _ : state) {
    // Alternate lights so that nothing is cached between calls.
    const Point3 light{(i++ & 1) ? 120.0 : -120.0, 30, 0};
    Reflection r = solve_reflection(eye, light, Point3::origin());
    benchmark::DoNotOptimize(r);
  }
}

void refracted_point(benchmark::State& state, double q, bool two_surfaces) {
  const Eye eye = bench_eye(q, two_surfaces);
  Point3 border[36];
  for (int k = 0; k < 36; ++k) border[k] = eye.pupil_border_point(k * 3.14159265358979 / 18);
  int i = 0;
  for (auto _ : state) {
    Refraction r = solve_refraction(eye, border[i++ % 36], Point3::origin());
    benchmark::DoNotOptimize(r);
  }
}

void BM_SphereGlint(benchmark::State& s) { glint(s, 0.0); }
void BM_ConicoidGlint(benchmark::State& s) { glint(s, -0.26); }
void BM_SphereRefractedPupilPoint(benchmark::State& s) { refracted_point(s, 0.0, false); }
void BM_ConicoidRefractedPupilPoint(benchmark::State& s) { refracted_point(s, -0.26, false); }
void BM_TwoSurfaceRefractedPupilPoint(benchmark::State& s) { refracted_point(s, -0.26, true); }

BENCHMARK(BM_SphereGlint);
BENCHMARK(BM_ConicoidGlint);
BENCHMARK(BM_SphereRefractedPupilPoint);
BENCHMARK(BM_ConicoidRefractedPupilPoint);
BENCHMARK(BM_TwoSurfaceRefractedPupilPoint);

}  // namespace
}  // namespace purkinje
