// The compare study's displacement field: zero for identical versions,
// and, for small changes, what a closed form and the solvers called
// directly say.

#include "purkinje/studies/compare.h"

#include "purkinje/studies/calibration.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <map>
#include <numbers>
#include <sstream>
#include <string>
#include <variant>

#include "purkinje/models/scene_file.h"
#include "purkinje/models/specular.h"
#include "purkinje/models/truth.h"

namespace purkinje::studies {
namespace {

const std::string kSourceDir = PURKINJE_SOURCE_DIR;

Scene bundled(const std::string& name) { return load_scene(kSourceDir + "/assets/scenes/" + name + ".json"); }

// The scene with its eye's model changed by `change`, its centre of
// rotation and optical axis kept.
template <class Change>
Scene with_model(const Scene& scene, Change change) {
  Scene out = scene;
  const Eye& eye = scene.eyes.front();
  EyeModel model = eye.model();
  change(model);
  Eye changed = Eye::with_rotation_center(model, eye.rotation_center(), eye.optical_axis());
  changed.set_appearance(eye.appearance());
  out.eyes = {changed};
  return out;
}

TEST(CompareField, IdenticalVersionsDisplaceNothing) {
  for (const char* name : {"remote", "headset"}) {
    for (const bool screen : {true, false}) {
      Scene scene = bundled(name);
      if (!screen) scene.screen.reset();
      CompareSettings settings;
      settings.grid = 3;
      const DisplacementField field = displacement_field(scene, scene, settings);
      EXPECT_EQ(field.on_screen, screen);
      ASSERT_EQ(field.points.size(), 9u);
      int compared = 0;
      for (const FieldPoint& p : field.points) {
        ASSERT_EQ(p.features.size(), scene.illuminators.size() + 2);
        for (const FeaturePair& f : p.features) {
          EXPECT_EQ(f.world_status, f.assumed_status) << name << " " << f.feature;
          if (const auto d = f.displacement()) {
            EXPECT_EQ(d->u, 0.0) << name << " " << f.feature;
            EXPECT_EQ(d->v, 0.0) << name << " " << f.feature;
            ++compared;
          }
          if (f.world_ellipse) {
            EXPECT_EQ(f.world_ellipse->semi_axis_1_px, f.assumed_ellipse->semi_axis_1_px);
            EXPECT_EQ(f.world_ellipse->semi_axis_2_px, f.assumed_ellipse->semi_axis_2_px);
          }
        }
      }
      EXPECT_GT(compared, 9 * 2) << name;  // the test compared pixels, not only statuses
    }
  }
}

// A spherical one-surface cornea, kappa 0: the eye fixates along the line
// through its centre of rotation, so a change of radius moves neither the
// optical axis nor the apex (rotation_center_depth is measured from it):
// the cornea's centre c moves by dc = -o dR. A convex spherical mirror
// far from the light L and the camera C (distances D >> R) reflects at
// p = c + R n, n the bisector of the unit directions u_L, u_C from c: to
// first order dp = dc + n dR + R dn, where the directions turn by
// du = -(I - u u^T) dc / D and the bisector by dn = (I - n n^T)(du_L +
// du_C) / |u_L + u_C|. The glint moves by J dp, J the camera's
// d(pixel)/d(point) at p. (Without the turn of n the field is 1.3% off.)
TEST(CompareField, GlintsMoveAsAConvexMirrorsFirstOrderClosedFormSays) {
  const Scene sphere = with_model(bundled("remote"), [](EyeModel& m) {
    m = keratometric_eye();
    m.kappa_horizontal_rad = m.kappa_vertical_rad = 0;
  });
  constexpr double dR = 1e-3;
  const Scene bigger = with_model(sphere, [](EyeModel& m) { m.anterior_cornea.radius_mm += dR; });
  CompareSettings settings;
  settings.grid = 3;
  const DisplacementField field = displacement_field(sphere, bigger, settings);
  const Camera& camera = sphere.cameras.front();
  int checked = 0;
  for (const FieldPoint& p : field.points) {
    const Eye eye = Eye::fixating(sphere.eyes.front().model(), sphere.eyes.front().rotation_center(),
                                  sphere.screen->at({p.x, p.y}));
    for (std::size_t i = 0; i < sphere.illuminators.size(); ++i) {
      const FeaturePair& f = p.features[i];
      const auto d = f.displacement();
      if (f.world_status != PathStatus::ok || !d) continue;
      const Reflection r = solve_reflection(eye, sphere.illuminators[i].position, camera.center());
      std::array<double, 6> j{};
      camera.project(r.point, j);
      const Point3 c = eye.cornea_center();
      const Vector3 dc = -eye.optical_axis().vector() * dR;
      const auto turn = [&](const Point3& x) {  // du for the direction from c to x
        const Vector3 to = x - c;
        const UnitVector3 u = UnitVector3::normalize(to);
        return (dc - u.vector() * dot(u, dc)) * (-1.0 / to.norm());
      };
      const Vector3 sum = (UnitVector3::normalize(sphere.illuminators[i].position - c).vector() +
                           UnitVector3::normalize(camera.center() - c).vector());
      const UnitVector3 n = UnitVector3::normalize(sum);
      const Vector3 du = turn(sphere.illuminators[i].position) + turn(camera.center());
      const Vector3 dn = (du - n.vector() * dot(n, du)) * (1.0 / sum.norm());
      const double radius = eye.model().anterior_cornea.radius_mm;
      const Vector3 dp = dc + n.vector() * dR + dn * radius;
      const double u = j[0] * dp.x + j[1] * dp.y + j[2] * dp.z, v = j[3] * dp.x + j[4] * dp.y + j[5] * dp.z;
      const double error = std::hypot(d->u - u, d->v - v), size = std::hypot(u, v);
      // The issue asks 1%; they agree to 0.05% (dR's own second order is 1e-4).
      EXPECT_LT(error, 0.002 * size) << f.feature << " at " << p.x << ", " << p.y << ": field (" << d->u << ", "
                                     << d->v << "), closed form (" << u << ", " << v << ")";
      ++checked;
    }
  }
  EXPECT_GE(checked, 9);
}

// The field against the solvers called directly on eyes built here: the
// glint by solve_reflection (a finite difference of the specular-path
// solver), the pupil centre by image_through_cornea (the refraction
// solver), for a change of the aqueous index.
TEST(CompareField, AgreesWithTheSolversCalledDirectly) {
  const Scene world = bundled("remote");
  const Scene assumed = with_model(world, [](EyeModel& m) { m.aqueous_index += 0.01; });
  CompareSettings settings;
  settings.grid = 2;
  const DisplacementField field = displacement_field(world, assumed, settings);
  const Camera& camera = world.cameras.front();
  for (const FieldPoint& p : field.points) {
    const Point3 target = world.screen->at({p.x, p.y});
    const Eye w = Eye::fixating(world.eyes.front().model(), world.eyes.front().rotation_center(), target);
    const Eye a = Eye::fixating(assumed.eyes.front().model(), assumed.eyes.front().rotation_center(), target);
    const RefractedImage before = image_through_cornea(w, camera, w.pupil_center());
    const RefractedImage after = image_through_cornea(a, camera, a.pupil_center());
    ASSERT_EQ(before.status, PathStatus::ok);
    const FeaturePair& center = p.features[world.illuminators.size()];
    ASSERT_EQ(center.feature, "pupil_center");
    const auto d = center.displacement();
    ASSERT_TRUE(d);
    EXPECT_NEAR(d->u, after.pixel.u - before.pixel.u, 1e-9);
    EXPECT_NEAR(d->v, after.pixel.v - before.pixel.v, 1e-9);
    EXPECT_GT(std::hypot(d->u, d->v), 1e-3);  // the index moved the pupil's image
    // The glints are the cornea's surface alone: the index moves none.
    for (std::size_t i = 0; i < world.illuminators.size(); ++i) {
      const Reflection r = solve_reflection(w, world.illuminators[i].position, camera.center());
      const Projection q = camera.project(r.point);
      ASSERT_TRUE(p.features[i].world);
      EXPECT_NEAR(p.features[i].world->u, q.pixel.u, 1e-9);
      EXPECT_EQ(p.features[i].displacement()->u, 0.0);
    }
  }
}

TEST(CompareField, RefusesVersionsThatCannotBeCompared) {
  const Scene remote = bundled("remote");
  Scene two_eyes = remote;
  two_eyes.eyes.push_back(remote.eyes.front());
  EXPECT_THROW(displacement_field(remote, two_eyes), std::invalid_argument);
  Scene one_light = remote;
  one_light.illuminators.pop_back();
  try {
    displacement_field(remote, one_light);
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "compare: the versions must have the same cameras and lights (world: 1 cameras, 2 lights; "
                           "assumed: 1 cameras, 1 lights)");
  }
  CompareSettings bad;
  bad.grid = 0;
  EXPECT_THROW(displacement_field(remote, remote, bad), std::invalid_argument);
  bad = {};
  bad.camera = 1;
  EXPECT_THROW(displacement_field(remote, remote, bad), std::invalid_argument);
}

TEST(CompareField, CsvHasARowPerTargetAndFeatureAndEmptyCellsForWhatDoesNotExist) {
  const Scene remote = bundled("remote");
  CompareSettings settings;
  settings.grid = 1;
  const std::string csv = displacement_csv(displacement_field(remote, remote, settings));
  EXPECT_EQ(csv.substr(0, csv.find('\n')),
            "target_x_mm,target_y_mm,feature,world_status,assumed_status,world_u_px,world_v_px,assumed_u_px,"
            "assumed_v_px,du_px,dv_px,displacement_px,world_semi_axis_1_px,world_semi_axis_2_px,world_angle_deg,"
            "assumed_semi_axis_1_px,assumed_semi_axis_2_px,assumed_angle_deg");
  EXPECT_NE(csv.find(",glint.led_left,ok,ok,"), std::string::npos);
  EXPECT_NE(csv.find(",0,0,0,,,,,,\n"), std::string::npos);  // a glint: no ellipse cells
  int rows = 0;
  for (char c : csv) rows += c == '\n';
  EXPECT_EQ(rows, 1 + 4);  // header, two glints, the pupil's centre and ellipse
}


// The consequences for a tracker: calibration with the rig as the tracker
// believes it (CalibrationSettings::tracker_rig), the frames rendered
// from the world.
CalibrationSettings small_calibration() {
  CalibrationSettings s;
  s.grid = 2;
  s.noise_frames = 0;
  return s;
}

// The mean of a frames.csv column.
double column_mean(const std::string& csv, const std::string& column) {
  std::istringstream in(csv);
  std::string line;
  std::getline(in, line);
  int index = 0, found = -1;
  std::istringstream header(line);
  for (std::string cell; std::getline(header, cell, ','); ++index) {
    if (cell == column) found = index;
  }
  double sum = 0;
  int n = 0;
  while (std::getline(in, line)) {
    // The position cell is quoted and may hold commas: count from the end.
    std::vector<std::string> cells;
    std::istringstream row(line);
    for (std::string cell; std::getline(row, cell, ',');) cells.push_back(cell);
    const std::size_t at = cells.size() - (index - static_cast<std::size_t>(found));
    sum += std::stod(cells[at]);
    ++n;
  }
  return sum / n;
}

TEST(CompareCalibration, ATrackerRigThatIsTheRigChangesNoNumber) {
  const Scene rig = bundled("remote");
  CalibrationSettings settings = small_calibration();
  const CalibrationStudy plain = run_calibration(rig, settings);
  settings.tracker_rig = rig;
  const CalibrationStudy believed = run_calibration(rig, settings);
  EXPECT_EQ(believed.frames_csv, plain.frames_csv);
  ASSERT_EQ(believed.runs.size(), plain.runs.size());
  for (std::size_t r = 0; r < plain.runs.size(); ++r) {
    const auto& a = plain.runs[r].results.entries();
    const auto& b = believed.runs[r].results.entries();
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
      if (a[i].key == "tracker_cornea_from") continue;  // says where the model came from
      EXPECT_TRUE(a[i].value == b[i].value) << a[i].key;
    }
  }
}

TEST(CompareCalibration, ALightTheTrackerBelievesElsewhereCostsGazeAccuracy) {
  const Scene rig = bundled("remote");
  Scene believed = rig;
  believed.illuminators[0].position.x += 5;  // the tracker's LED 5 mm from the real one
  CalibrationSettings settings = small_calibration();
  const double right = column_mean(run_calibration(rig, settings).frames_csv, "model_error_deg");
  settings.tracker_rig = believed;
  const double wrong = column_mean(run_calibration(rig, settings).frames_csv, "model_error_deg");
  EXPECT_GT(wrong, right + 0.05) << "right " << right << " deg, wrong " << wrong << " deg";

  Scene one_light = rig;
  one_light.illuminators.pop_back();
  settings.tracker_rig = one_light;
  EXPECT_THROW(check_calibration_rig(rig, "rig.json", settings), std::invalid_argument);
}

// Exact features: the features where the labels put them, no render.
TEST(CompareCalibration, WithExactFeaturesTheTrackersOwnEyeGivesGazeToTheSolversTolerance) {
  // The keratometric eye is what the model-based tracker assumes (one
  // sphere, one index): believing it, from exact features, gaze is exact
  // but for the fit's tolerances, at home and after head moves.
  const Scene rig = with_model(bundled("remote"), [](EyeModel& m) {
    const EyeModel k = keratometric_eye();
    m.anterior_cornea = k.anterior_cornea;
    m.posterior_cornea.reset();
    m.aqueous_index = k.aqueous_index;
  });
  CalibrationSettings settings = CompareStudySettings::default_calibration();
  settings.grid = 3;
  settings.head_moves = default_head_moves(rig);
  const CalibrationStudy study = run_calibration(rig, settings);
  ASSERT_EQ(study.panels.size(), 3u);
  for (const SimulationRun& run : study.runs) {
    if (run.algorithm != "model-based" || run.case_name == "calibration") continue;
    const auto worst = run.results.number("gaze_error_max");
    ASSERT_TRUE(worst) << run.case_name;
    EXPECT_LT(*worst, 1e-3) << run.case_name;
  }
  EXPECT_EQ(calibration_frames(settings), 9u + 3 * 9);
}

CompareStudySettings small_study() {
  CompareStudySettings s;
  s.calibration.head_moves = default_head_moves(bundled("remote"));
  s.field.grid = 3;
  s.calibration.grid = 3;
  s.render.seed = 3;
  return s;
}

TEST(CompareStudy, IdenticalVersionsCostNothingAnywhere) {
  const Scene rig = bundled("remote");
  int steps = 0;
  const CompareStudy study = run_compare(rig, rig, small_study(), [&] { ++steps; });
  EXPECT_EQ(static_cast<std::size_t>(steps), compare_steps(rig, small_study()));
  ASSERT_TRUE(study.baseline && study.assumed && study.world_image && study.assumed_image);
  ASSERT_EQ(study.gaze.size(), 3u * 2 * 9);  // positions, methods, targets
  for (const GazeChange& g : study.gaze) {
    ASSERT_TRUE(g.change_deg) << g.position << " " << g.method;
    EXPECT_EQ(*g.change_deg, 0.0);
    EXPECT_EQ(*g.baseline_error_deg, *g.assumed_error_deg);
  }
  EXPECT_EQ(study.world_image->electrons.values, study.assumed_image->electrons.values);
  EXPECT_EQ(study.world_image->sensor.values, study.assumed_image->sensor.values);
  for (const SimulationRun& run : study.summary) {
    for (const char* key : {"displacement_max", "change_max", "electrons_difference_max", "sensor_difference_max"}) {
      if (const auto v = run.results.number(key)) {
        EXPECT_EQ(*v, 0.0) << run.case_name << " " << key;
      }
    }
  }
}

TEST(CompareStudy, ASphericalTrackerOnTheNavarroEyeMovesGlintsAndGaze) {
  const Scene world = bundled("remote");  // Navarro: aspheric, two surfaces
  const Scene spherical = with_model(world, [](EyeModel& m) {
    m.anterior_cornea = {7.8, 0};
    m.posterior_cornea.reset();
    m.aqueous_index = 1.3375;
  });
  CompareStudySettings settings = small_study();
  settings.images = false;
  const CompareStudy study = run_compare(world, spherical, settings);
  EXPECT_FALSE(study.world_image);
  int runs_with_change = 0;
  for (const SimulationRun& run : study.summary) {
    if (run.case_name.starts_with("gaze: ") && run.algorithm == "model-based") {
      ++runs_with_change;
      ASSERT_TRUE(run.results.number("change_max")) << run.case_name;
      EXPECT_GT(*run.results.number("change_max"), 0.01) << run.case_name;
    }
    if (run.case_name == "displacement" && run.algorithm.starts_with("glint.")) {
      ASSERT_TRUE(run.results.number("displacement_max")) << run.algorithm;
      EXPECT_GT(*run.results.number("displacement_max"), 0.05) << run.algorithm;
    }
  }
  EXPECT_EQ(runs_with_change, 3);
  const std::string csv = gaze_change_csv(study.gaze);
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 1 + 3 * 2 * 9);
}

TEST(CompareStudy, WithoutAScreenItComparesOnACapAndSaysWhyItDidNotCalibrate) {
  Scene world = bundled("remote");
  world.screen.reset();
  CompareStudySettings settings = small_study();
  settings.images = false;
  const CompareStudy study = run_compare(world, world, settings);
  EXPECT_FALSE(study.field.on_screen);
  EXPECT_FALSE(study.baseline);
  EXPECT_NE(study.calibration_skipped.find("screen"), std::string::npos) << study.calibration_skipped;
  EXPECT_EQ(compare_steps(world, settings), 0u);
}

// Sweeps: one parameter of the assumed version, its values from the
// world's own on.
TEST(CompareSweep, FromTheWorldsOwnValueTheCostGrowsWithTheChange) {
  const Scene world = bundled("remote");  // Navarro: anterior Q = -0.26
  const double own = world.eyes.front().model().anterior_cornea.asphericity;
  CompareStudySettings settings = small_study();
  SweepSettings sweep{"cornea_asphericity", own, 0, 3, 2, 5};
  int steps = 0;
  const Sweep result = run_sweep(world, settings, sweep, [&] { ++steps; });
  EXPECT_EQ(static_cast<std::size_t>(steps), sweep_steps(world, settings, sweep));
  ASSERT_EQ(result.values.size(), 3u);
  EXPECT_EQ(result.values.front(), own);
  EXPECT_EQ(result.values[1], own / 2);
  EXPECT_EQ(result.values.back(), 0.0);
  // The largest glint displacement and model-based gaze change at home, per value.
  std::vector<double> glint, gaze;
  for (const auto& summary : result.summaries) {
    double g = 0;
    for (const SimulationRun& run : summary) {
      if (run.case_name == "displacement" && run.algorithm.starts_with("glint.")) {
        g = std::max(g, *run.results.number("displacement_max"));
      }
      if (run.case_name == "gaze: home" && run.algorithm == "model-based") gaze.push_back(*run.results.number("change_max"));
    }
    glint.push_back(g);
  }
  ASSERT_EQ(gaze.size(), 3u);
  EXPECT_EQ(glint[0], 0.0);  // the world's own value: the same rig
  EXPECT_EQ(gaze[0], 0.0);
  EXPECT_GT(glint[1], 0.0);
  EXPECT_GT(glint[2], glint[1]);
  EXPECT_GT(gaze[2], gaze[1]);
  // The noise floor, measured on two renders.
  ASSERT_TRUE(result.noise);
  EXPECT_EQ(result.noise->frames, 2);
  EXPECT_GT(result.noise->glint_px, 0.0);
  EXPECT_LT(result.noise->glint_px, 0.5);
  ASSERT_TRUE(result.gaze_noise_deg);
  EXPECT_GT(*result.gaze_noise_deg, 0.0);
  const std::string csv = sweep_csv(result);
  // Per value: 4 features, then per position both methods' gaze change and
  // the model-based cornea's depth error and share within 3 s.d.
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 1 + 3 * (4 + 3 * (2 + 2)));
  EXPECT_NE(sweep_json(result).find("\"parameter\": \"cornea_asphericity\""), std::string::npos);
}

TEST(CompareSweep, ParametersChangeWhatTheyNameAndRefuseWhatTheEyeCannotBe) {
  const Scene world = bundled("remote");
  const Scene moved = with_parameter(world, "led_offset_x", 5);
  EXPECT_EQ(moved.illuminators[0].position.x, world.illuminators[0].position.x + 5);
  EXPECT_EQ(moved.illuminators[1].position.x, world.illuminators[1].position.x);
  const Scene kappa = with_parameter(world, "kappa_horizontal", 2);
  EXPECT_NEAR(kappa.eyes.front().model().kappa_horizontal_rad, 2 * std::numbers::pi / 180, 1e-15);
  EXPECT_EQ(kappa.eyes.front().rotation_center(), world.eyes.front().rotation_center());
  const Scene radius = with_parameter(world, "cornea_radius", 7.6);
  EXPECT_EQ(radius.eyes.front().model().anterior_cornea.radius_mm, 7.6);
  EXPECT_EQ(radius.eyes.front().model().anterior_cornea.asphericity,
            world.eyes.front().model().anterior_cornea.asphericity);
  // Each parameter at a value a human eye can have, and at the world's own.
  const std::map<std::string, double> plausible = {
      {"cornea_radius", 7.6},        {"cornea_asphericity", -0.1},  {"aqueous_index", 1.336},
      {"iris_depth", 3.4},           {"pupil_decentration_x", 0.2}, {"pupil_decentration_y", -0.1},
      {"kappa_horizontal", 4},       {"kappa_vertical", 2},         {"led_offset_x", 1},
      {"led_offset_y", 1},           {"led_offset_z", 1}};
  ASSERT_EQ(plausible.size(), sweep_parameters().size());
  for (const SweepParameter& p : sweep_parameters()) EXPECT_NO_THROW(with_parameter(world, p.name, plausible.at(p.name)));
  const EyeModel& own = world.eyes.front().model();
  EXPECT_EQ(with_parameter(world, "aqueous_index", own.aqueous_index).eyes.front().world_from_eye().translation(),
            world.eyes.front().world_from_eye().translation());
  const auto message = [&](const std::string& parameter, double value) {
    try {
      with_parameter(world, parameter, value);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("(accepted)");
  };
  EXPECT_NE(message("cornea_radios", 7).find("unknown parameter \"cornea_radios\" (known: cornea_radius,"),
            std::string::npos);
  EXPECT_NE(message("cornea_radius", -1).find("sweep: cornea_radius = -1: the eye's anatomy refuses it"),
            std::string::npos)
      << message("cornea_radius", -1);
  EXPECT_NE(message("aqueous_index", 0.9).find("must be more than 1"), std::string::npos);
  EXPECT_THROW(run_sweep(world, small_study(), SweepSettings{"cornea_radius", 7, 7, 3, 0, 1}), std::invalid_argument);
  EXPECT_THROW(run_sweep(world, small_study(), SweepSettings{"cornea_radius", 7, 8, 1, 0, 1}), std::invalid_argument);
}

// Eye models by preset name or file: the anatomy replaced, the eye's place,
// gaze and pupil kept.
TEST(CompareEyeModel, APresetOrAFileReplacesTheAnatomyAndKeepsThePlaceAndPupil) {
  Scene world = with_model(bundled("remote"), [](EyeModel& m) { m.pupil_radius_mm = 2.5; });
  const Eye& eye = world.eyes.front();
  const Scene k = with_eye_model(world, "keratometric");
  const Eye& kept = k.eyes.front();
  EXPECT_EQ(kept.model().anterior_cornea.radius_mm, keratometric_eye().anterior_cornea.radius_mm);
  EXPECT_FALSE(kept.model().posterior_cornea);
  EXPECT_EQ(kept.model().kappa_horizontal_rad, keratometric_eye().kappa_horizontal_rad);
  EXPECT_EQ(kept.model().pupil_radius_mm, 2.5);
  EXPECT_LT(distance(kept.rotation_center(), eye.rotation_center()), 1e-12);
  EXPECT_LT(angle_between(kept.optical_axis().vector(), eye.optical_axis().vector()), 1e-15);
  EXPECT_EQ(kept.appearance().iris_seed, eye.appearance().iris_seed);

  const std::string dir = ::testing::TempDir();
  const auto file = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir + name) << text;
    return dir + name;
  };
  // The file naming the scene's own model and pupil: the same anatomy.
  const Scene remote = bundled("remote");
  const Scene same = with_eye_model(remote, file("navarro.json", R"({"model": "navarro", "pupil": {"radius_mm": 2.0}})"));
  const EyeModel& a = same.eyes.front().model();
  const EyeModel& b = remote.eyes.front().model();
  EXPECT_EQ(a.anterior_cornea.asphericity, b.anterior_cornea.asphericity);
  EXPECT_EQ(a.aqueous_index, b.aqueous_index);
  EXPECT_EQ(a.pupil_radius_mm, b.pupil_radius_mm);
  EXPECT_EQ(a.kappa_horizontal_rad, b.kappa_horizontal_rad);
  const std::string flat = file("flat.json", R"({"model": "navarro", "cornea": {"asphericity": 0}})");
  EXPECT_EQ(with_eye_model(world, flat).eyes.front().model().anterior_cornea.asphericity, 0.0);

  const auto message = [&](const std::string& model) {
    try {
      with_eye_model(world, model);
    } catch (const SceneError& e) {
      return std::string(e.what());
    }
    return std::string("(accepted)");
  };
  const std::string placed = file("placed.json", R"({"model": "navarro", "position": {"rotation_center_mm": [0, 0, 600]}})");
  EXPECT_NE(message(placed).find("placed.json: key \"position\": an eye-model file holds only anatomy"),
            std::string::npos)
      << message(placed);
  const std::string bad = file("bad.json", R"({"cornea": {"radius_mm": -1}})");
  EXPECT_NE(message(bad).find("bad.json"), std::string::npos) << message(bad);
  EXPECT_NE(message(bad).find("radius_mm"), std::string::npos) << message(bad);
  EXPECT_NE(message("navaro").find("navaro: cannot open the eye-model file (nor is it a preset: keratometric"),
            std::string::npos)
      << message("navaro");
  EXPECT_NE(message(file("list.json", "[1]")).find("must be a JSON object"), std::string::npos);
}

}  // namespace
}  // namespace purkinje::studies
