// Speed against error of the fast renderer on the bundled scenes.
//
// Time per image covers render() (tracing, iris caches or photons, glints,
// optics and sensor), not file writing. With PURKINJE_BENCH_ERROR=1 each
// benchmark also reports `rel_error`: the RMSE of the noise-free linear
// image against a converged brute-force reference (reference mode,
// PURKINJE_BENCH_REFERENCE_SPP samples per pixel, default 1024, and 2^25
// photons per light), divided by the reference's mean over pixels where it
// is non-zero, leaving out glint pixels (glint AOV > 1%), as the renderer
// issue defines it. The reference takes minutes; it is rendered once per
// scene and run.

#include <benchmark/benchmark.h>
#include <embree3/rtcore.h>
#include <sys/resource.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <barrier>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <map>
#include <span>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "purkinje/models/scene_file.h"
#include "purkinje/renderer/ray_tracer.h"
#include "purkinje/renderer/render.h"
#include "scene_geometry.h"

namespace purkinje::renderer {
namespace {

// A bundled scene by name; "<name>+face": that scene's one eye given a
// periocular face with every default (the face's cost on the same view);
// "<name>+face+lashes": and default lashes; "<name>-lenses": without its
// spectacle lenses (the lenses' cost on the same view); "<name>-brows":
// its faces without their brows (the brows' cost).
const Scene& scene(const std::string& name) {
  static std::map<std::string, Scene> scenes;
  auto it = scenes.find(name);
  if (it == scenes.end()) {
    const std::size_t plus = std::min({name.find("+face"), name.find("-lenses"), name.find("-brows")});
    const bool lashes = name.ends_with("+lashes");
    Scene s = load_scene(std::string(PURKINJE_SOURCE_DIR) + "/assets/scenes/" + name.substr(0, plus) + ".json");
    if (name.ends_with("-lenses")) s.spectacle_lenses.clear();
    if (name.ends_with("-brows")) {
      for (Eye& eye : s.eyes) {
        EyeAppearance a = eye.appearance();
        if (a.face) a.face->brows.reset();
        eye.set_appearance(a);
      }
    }
    if (name.find("+face") != std::string::npos) {
      if (s.eyes.size() != 1) throw std::invalid_argument(name + ": a default face is a right eye's; one eye only");
      for (Eye& eye : s.eyes) {
        EyeAppearance a = eye.appearance();
        a.face = Face{};
        if (lashes) a.face->lashes = Lashes{};
        eye.set_appearance(a);
      }
    }
    it = scenes.emplace(name, std::move(s)).first;
  }
  return it->second;
}

const RenderResult& converged(const std::string& name) {
  static std::map<std::string, RenderResult> results;
  auto it = results.find(name);
  if (it == results.end()) {
    RenderOptions options;
    options.mode = RenderMode::reference;
    const char* spp = std::getenv("PURKINJE_BENCH_REFERENCE_SPP");
    options.samples_per_pixel = spp ? std::atoi(spp) : 1024;
    options.edge_samples_per_pixel = 0;  // the same rays in every pixel
    options.reference_photons_per_light = std::int64_t{1} << 25;
    options.noise = false;
    options.seed = 12345;
    it = results.emplace(name, render(scene(name), 0, options)).first;
  }
  return it->second;
}

double relative_error(const RenderResult& r, const RenderResult& ref) {
  const ImagePlane* glint = nullptr;
  for (const NamedPlane& p : ref.aovs) {
    if (p.name == "glint") glint = &p.plane;
  }
  double sum_sq = 0, sum_ref = 0;
  long n = 0, lit = 0;
  for (std::size_t i = 0; i < ref.electrons.values.size(); ++i) {
    if (glint && glint->values[i] > 0.01f) continue;
    const double d = double(r.electrons.values[i]) - ref.electrons.values[i];
    sum_sq += d * d;
    ++n;
    if (ref.electrons.values[i] > 0) {
      sum_ref += ref.electrons.values[i];
      ++lit;
    }
  }
  return std::sqrt(sum_sq / n) / (sum_ref / lit);
}

// Arguments: samples per pixel, and edge samples per pixel (adaptive
// sampling; 0: off).
RenderOptions bench_options(const benchmark::State& state, RenderMode mode) {
  RenderOptions options;
  options.mode = mode;
  options.reference_photons_per_light = std::int64_t{1} << 20;
  options.samples_per_pixel = static_cast<int>(state.range(0));
  options.edge_samples_per_pixel = static_cast<int>(state.range(1));
  options.noise = false;
  return options;
}

void render_scene(benchmark::State& state, const std::string& name, RenderMode mode) {
  const RenderOptions options = bench_options(state, mode);
  // Into one result, as a loop over a data set renders (its memory reused).
  RenderResult last;
  for (auto _ : state) {
    render(scene(name), 0, options, last);
    benchmark::DoNotOptimize(last.electrons.values.data());
  }
  state.counters["images_per_s"] = benchmark::Counter(static_cast<double>(state.iterations()),
                                                      benchmark::Counter::kIsRate);
  if (const char* e = std::getenv("PURKINJE_BENCH_ERROR"); e && std::string(e) == "1") {
    state.counters["rel_error"] = relative_error(last, converged(name));
  }
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  state.counters["peak_rss_mb"] = usage.ru_maxrss / 1024.0;
}

// Each iteration runs work(0) here and work(1) on a second thread at once,
// in step; counts two images an iteration.
template <typename Work>
void in_pairs(benchmark::State& state, const Work& work) {
  std::barrier step(2);
  bool done = false;  // written before a barrier, read after it
  std::thread other([&] {
    for (;;) {
      step.arrive_and_wait();
      if (done) return;
      work(1);
      step.arrive_and_wait();
    }
  });
  for (auto _ : state) {
    step.arrive_and_wait();
    work(0);
    step.arrive_and_wait();
  }
  done = true;
  step.arrive_and_wait();
  other.join();
  state.counters["images_per_s"] = benchmark::Counter(2.0 * static_cast<double>(state.iterations()),
                                                      benchmark::Counter::kIsRate);
}

// Throughput as a data set is made: two images at once, one thread each
// (no serial phases, no synchronisation), on a 2-core machine; each worker
// renders into its own result, as a data set's workers would.
void render_pairs(benchmark::State& state, const std::string& name) {
  RenderOptions options = bench_options(state, RenderMode::fast);
  options.threads = 1;
  const Scene& s = scene(name);
  RenderResult results[2];
  in_pairs(state, [&](int k) {
    render(s, 0, options, results[k]);
    benchmark::DoNotOptimize(results[k].electrons.values.data());
  });
}

// The floor under a render's time: per image, the scene's ray tracer
// built (as render() builds it for every image: the face's mesh follows
// the eye, and Embree commits it) and one camera ray per pixel through
// its centre, traced in packets as the fast mode traces its first pass;
// no shading, no lights, no caches, nothing after. Argument 0: the build
// alone; 1: and the rays. Pairs, as above: two images at once, one thread
// each.
void camera_rays_pairs(benchmark::State& state, const std::string& name) {
  const Scene& s = scene(name);
  const Camera& camera = s.cameras.at(0);
  const int width = camera.intrinsics().width, height = camera.intrinsics().height;
  const bool with_rays = state.range(0) == 1;
  in_pairs(state, [&](int) {
    const RayTracer tracer(s);
    if (!with_rays) return;
    // As the first pass: a packet's rays made along a row, traced, their
    // hits read (an image's rays and hits held at once would stream 200 MB
    // through memory, which no render does).
    const int packet = tracer.packet_width();
    std::array<Ray, 16> rays;
    std::array<Hit, 16> hits;
    double sum = 0;
    for (int v = 0; v < height; ++v) {
      for (int first = 0; first < width; first += packet) {
        const int count = std::min(packet, width - first);
        for (int i = 0; i < count; ++i) rays[i] = {camera.center(), camera.back_project({double(first + i), double(v)})};
        tracer.intersect(std::span<const Ray>(rays.data(), count), std::span<Hit>(hits.data(), count));
        for (int i = 0; i < count; ++i) sum += hits[i].t;
      }
    }
    benchmark::DoNotOptimize(sum);
  });
}

// What Embree alone spends on a scene's meshes (the faces; both eyes' in
// remote_face): their triangles in a plain Embree scene, built once
// outside the timing with the renderer's build quality, no filters (float
// hits, not the renderer's double), no eyes, no hairs; per image one
// camera ray per pixel through its centre in packets of 8 along a row
// (argument 0), and then, for every camera ray that meets a triangle, one
// shadow ray to each light its face turns to (argument 1: what a
// Lambertian pixel's direct light needs at the least). The device is
// configured as the renderer's (PURKINJE_EMBREE_CONFIG, checked). Pairs,
// as above. Counters per image: camera rays that meet a triangle, shadow
// rays traced, and those that reach their light.
void embree_alone_pairs(benchmark::State& state, const std::string& name) {
  const Scene& s = scene(name);
  const Camera& camera = s.cameras.at(0);
  const int width = camera.intrinsics().width, height = camera.intrinsics().height;
  const bool with_shadows = state.range(0) == 1;
  RTCDevice device = rtcNewDevice(embree_device().config.c_str());
  if (!device) throw std::runtime_error("Embree: no device");
  RTCScene rtc = rtcNewScene(device);
  rtcSetSceneBuildQuality(rtc, RTC_BUILD_QUALITY_HIGH);
  const SceneGeometry geometry = build_scene_geometry(s);
  std::size_t triangles = 0;
  for (const auto& mesh : geometry.meshes) {
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                          3 * sizeof(float), mesh->vertices().size()));
    auto* t = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                             3 * sizeof(unsigned), mesh->triangles().size()));
    for (std::size_t i = 0; i < mesh->vertices().size(); ++i) {
      const Point3& p = mesh->vertices()[i];
      v[3 * i + 0] = static_cast<float>(p.x);
      v[3 * i + 1] = static_cast<float>(p.y);
      v[3 * i + 2] = static_cast<float>(p.z);
    }
    for (std::size_t i = 0; i < mesh->triangles().size(); ++i) {
      for (int k = 0; k < 3; ++k) t[3 * i + k] = mesh->triangles()[i][k];
    }
    triangles += mesh->triangles().size();
    rtcSetGeometryBuildQuality(g, RTC_BUILD_QUALITY_HIGH);
    rtcCommitGeometry(g);
    rtcAttachGeometry(rtc, g);
    rtcReleaseGeometry(g);
  }
  rtcCommitScene(rtc);
  if (rtcGetDeviceError(device) != RTC_ERROR_NONE) throw std::runtime_error("Embree: building the scene failed");
  const Point3 o = camera.center();
  std::vector<Point3> lights;
  for (const Illuminator& l : s.illuminators) lights.push_back(l.position);
  constexpr float kInactive = -std::numeric_limits<float>::infinity();  // tfar < tnear: no lane traced
  std::atomic<long> hits{0}, shadow_rays{0}, lit{0};
  in_pairs(state, [&](int) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit8 packet;
    RTCRay8 shadow;
    alignas(32) int valid[8];
    alignas(32) int hit[8];
    long my_hits = 0, my_shadow_rays = 0, my_lit = 0;
    for (int v = 0; v < height; ++v) {
      for (int first = 0; first < width; first += 8) {
        for (int i = 0; i < 8; ++i) {
          const Vector3 d = camera.back_project({double(std::min(first + i, width - 1)), double(v)}).vector();
          valid[i] = first + i < width ? -1 : 0;
          packet.ray.org_x[i] = float(o.x);
          packet.ray.org_y[i] = float(o.y);
          packet.ray.org_z[i] = float(o.z);
          packet.ray.dir_x[i] = float(d.x);
          packet.ray.dir_y[i] = float(d.y);
          packet.ray.dir_z[i] = float(d.z);
          packet.ray.tnear[i] = 0;
          packet.ray.tfar[i] = valid[i] ? std::numeric_limits<float>::infinity() : kInactive;
          packet.ray.time[i] = 0;
          packet.ray.mask[i] = ~0u;
          packet.ray.flags[i] = 0;
          packet.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
        }
        rtcIntersect8(valid, rtc, &context, &packet);
        for (int i = 0; i < 8; ++i) {
          hit[i] = valid[i] && packet.hit.geomID[i] != RTC_INVALID_GEOMETRY_ID ? -1 : 0;
          my_hits += hit[i] != 0;
        }
        if (!with_shadows) continue;
        for (const Point3& l : lights) {
          for (int i = 0; i < 8; ++i) {
            // From just before the hit toward the light (tfar 1: the
            // light), if the face there turns to it (the normal's side
            // the camera sees).
            const float t = packet.ray.tfar[i] * 0.9999f;
            shadow.org_x[i] = packet.ray.org_x[i] + t * packet.ray.dir_x[i];
            shadow.org_y[i] = packet.ray.org_y[i] + t * packet.ray.dir_y[i];
            shadow.org_z[i] = packet.ray.org_z[i] + t * packet.ray.dir_z[i];
            shadow.dir_x[i] = float(l.x) - shadow.org_x[i];
            shadow.dir_y[i] = float(l.y) - shadow.org_y[i];
            shadow.dir_z[i] = float(l.z) - shadow.org_z[i];
            const float to_camera = -(packet.hit.Ng_x[i] * packet.ray.dir_x[i] + packet.hit.Ng_y[i] * packet.ray.dir_y[i] +
                                      packet.hit.Ng_z[i] * packet.ray.dir_z[i]);
            const float to_light = packet.hit.Ng_x[i] * shadow.dir_x[i] + packet.hit.Ng_y[i] * shadow.dir_y[i] +
                                   packet.hit.Ng_z[i] * shadow.dir_z[i];
            valid[i] = hit[i] && to_camera * to_light > 0 ? -1 : 0;
            shadow.tnear[i] = 0;
            shadow.tfar[i] = valid[i] ? 0.9999f : kInactive;
            shadow.time[i] = 0;
            shadow.mask[i] = ~0u;
            shadow.flags[i] = 0;
          }
          rtcOccluded8(valid, rtc, &context, &shadow);  // an occluded ray's tfar becomes -inf
          for (int i = 0; i < 8; ++i) {
            my_shadow_rays += valid[i] != 0;
            my_lit += valid[i] && shadow.tfar[i] >= 0;
          }
        }
      }
    }
    hits += my_hits;
    shadow_rays += my_shadow_rays;
    lit += my_lit;
  });
  const double images = 2.0 * static_cast<double>(state.iterations());
  state.counters["triangles"] = static_cast<double>(triangles);
  state.counters["hits"] = static_cast<double>(hits) / images;
  state.counters["shadow_rays"] = static_cast<double>(shadow_rays) / images;
  state.counters["lit"] = static_cast<double>(lit) / images;
  rtcReleaseScene(rtc);
  rtcReleaseDevice(device);
}

void sampling_args(benchmark::internal::Benchmark* b) {
  for (const auto& [spp, edge] : std::vector<std::pair<int, int>>{{1, 0}, {1, 6}, {1, 10}, {1, 12}, {1, 16}, {1, 24}, {2, 16}, {4, 0}, {8, 0}}) {
    b->Args({spp, edge});
  }
}

void BM_RenderRemote(benchmark::State& s) { render_scene(s, "remote", RenderMode::fast); }
void BM_RenderHeadset(benchmark::State& s) { render_scene(s, "headset", RenderMode::fast); }
void BM_RenderRemoteFace(benchmark::State& s) { render_scene(s, "remote+face", RenderMode::fast); }
void BM_RenderHeadsetFace(benchmark::State& s) { render_scene(s, "headset+face", RenderMode::fast); }
void BM_RenderRemotePairs(benchmark::State& s) { render_pairs(s, "remote"); }
void BM_RenderHeadsetPairs(benchmark::State& s) { render_pairs(s, "headset"); }
void BM_RenderRemoteFacePairs(benchmark::State& s) { render_pairs(s, "remote+face"); }
void BM_RenderHeadsetFacePairs(benchmark::State& s) { render_pairs(s, "headset+face"); }
void BM_RenderRemoteFaceLashes(benchmark::State& s) { render_scene(s, "remote+face+lashes", RenderMode::fast); }
void BM_RenderHeadsetFaceLashes(benchmark::State& s) { render_scene(s, "headset+face+lashes", RenderMode::fast); }
void BM_RenderRemoteFaceLashesPairs(benchmark::State& s) { render_pairs(s, "remote+face+lashes"); }
void BM_RenderHeadsetFaceLashesPairs(benchmark::State& s) { render_pairs(s, "headset+face+lashes"); }
// Both eyes in a 1280 x 960 view of the whole face.
void BM_RenderRemoteBothEyesPairs(benchmark::State& s) { render_pairs(s, "remote_face"); }
void BM_RenderRemoteBothEyesNoBrowsPairs(benchmark::State& s) { render_pairs(s, "remote_face-brows"); }
void BM_RenderRemoteGlassesPairs(benchmark::State& s) { render_pairs(s, "remote_glasses"); }
void BM_RenderRemoteGlassesFramePairs(benchmark::State& s) { render_pairs(s, "remote_glasses-lenses"); }
void BM_CameraRaysRemoteBothEyesPairs(benchmark::State& s) { camera_rays_pairs(s, "remote_face"); }
void BM_EmbreeAloneRemoteBothEyesPairs(benchmark::State& s) { embree_alone_pairs(s, "remote_face"); }
void BM_EmbreeAloneHeadsetFacePairs(benchmark::State& s) { embree_alone_pairs(s, "headset+face"); }
void BM_CameraRaysHeadsetFaceLashesPairs(benchmark::State& s) { camera_rays_pairs(s, "headset+face+lashes"); }
void BM_CameraRaysRemoteFaceLashesPairs(benchmark::State& s) { camera_rays_pairs(s, "remote+face+lashes"); }
BENCHMARK(BM_CameraRaysRemoteBothEyesPairs)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_EmbreeAloneRemoteBothEyesPairs)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_EmbreeAloneHeadsetFacePairs)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_CameraRaysHeadsetFaceLashesPairs)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_CameraRaysRemoteFaceLashesPairs)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_RenderRemote)->Apply(sampling_args)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_RenderHeadset)->Apply(sampling_args)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_RenderRemotePairs)->Args({1, 0})->Args({1, 16})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_RenderHeadsetPairs)->Args({1, 10})->Args({1, 12})->Args({1, 16})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_RenderRemoteFace)->Args({1, 0})->Args({1, 16})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_RenderHeadsetFace)->Args({1, 10})->Args({1, 16})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_RenderRemoteFacePairs)->Args({1, 0})->Args({1, 16})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_RenderHeadsetFacePairs)->Args({1, 0})->Args({1, 10})->Args({1, 16})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_RenderRemoteFaceLashes)->Args({1, 0})->Args({1, 16})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_RenderHeadsetFaceLashes)->Args({1, 10})->Args({1, 16})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_RenderRemoteFaceLashesPairs)->Args({1, 0})->Args({1, 16})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_RenderHeadsetFaceLashesPairs)->Args({1, 0})->Args({1, 10})->Args({1, 16})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_RenderRemoteBothEyesPairs)->Args({1, 0})->Args({1, 16})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_RenderRemoteBothEyesNoBrowsPairs)->Args({1, 0})->Args({1, 16})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_RenderRemoteGlassesPairs)->Args({1, 0})->Args({1, 16})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_RenderRemoteGlassesFramePairs)->Args({1, 0})->Args({1, 16})->Unit(benchmark::kMillisecond)->UseRealTime();
// The brute-force mode at the same settings, for the side-by-side table
// (2^20 photons per light: its photon tracing is a fixed cost per image).
// Only at 1 sample per pixel unless PURKINJE_BENCH_ERROR=1: CI's brief run
// must stay brief.
const bool reference_benchmarks_registered = [] {
  const char* e = std::getenv("PURKINJE_BENCH_ERROR");
  const bool full = e && std::string(e) == "1";
  for (const char* name : {"remote", "headset"}) {
    auto* b = benchmark::RegisterBenchmark(
        (std::string("BM_Reference") + (name[0] == 'r' ? "Remote" : "Headset")).c_str(),
        [name](benchmark::State& s) { render_scene(s, name, RenderMode::reference); });
    b->Args({1, 0})->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
    if (full) b->Args({4, 0})->Args({16, 0})->Args({64, 0});
  }
  return true;
}();

}  // namespace
}  // namespace purkinje::renderer
