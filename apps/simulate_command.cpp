// glasspiv simulate: a simulated PIV experiment with its ground truth
// (sim/piv_experiment.h; docs/simulation.md "Simulated experiments"): per
// camera the distorted frames A and B, the same camera's frames with the glass
// removed, and the true displacement on the PIV grid; metadata.json with every
// setting and the seed.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <sstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "apps/cli_checks.h"
#include "apps/cli_files.h"
#include "apps/commands.h"
#include "apps/correction_setup.h"
#include "piv/piv_evaluate.h"
#include "piv/vector_file.h"
#include "sim/piv_experiment.h"
#include "sim/vtk_flow_file.h"
#include "util/json_document.h"
#include "util/atomic_file.h"
#include "util/image_file.h"
#include "util/input_error.h"
#include "util/progress_bar.h"
#include "util/stopwatch.h"

namespace glasspiv {
namespace {
namespace fs = std::filesystem;

struct SimulateOptions {
  std::string scene, flow, output, camera = "all", vtk_array;
  double dt_s = 1e-3, time_a_s = 0, density_ppp = 0.03, particle_px = 2.5, vtk_mm_per_length = 1000;
  double peak_fraction = 0.5;
  int bit_depth = 12, binning = 1, truth_window_px = 32, threads = 0;
  std::uint64_t seed = 1;
};

constexpr const char* kFlowHelp =
    "uniform:UX,UY,UZ (m/s, world) | rotation:OMEGA[,AX,AY,AZ[,CX,CY,CZ]] (rad/s; default axis the sheet normal "
    "through its origin) | vortex:GAMMA,CORE_MM[,NU[,CX,CY,CZ]] (Lamb-Oseen, m^2/s, about the sheet normal) | "
    "poiseuille:U,HALF_WIDTH_MM (along s, walls across t through the sheet origin) | "
    "stokes:RADIUS_MM,UX,UY,UZ[,CX,CY,CZ] (flow past a sphere at the sheet origin) | vtk:FILE (.vti, .vtu, .vtk)";

// "name:a,b,c" -> name and numbers; InputError naming --flow otherwise.
std::pair<std::string, std::vector<double>> split_flow(const std::string& spec) {
  const auto colon = spec.find(':');
  const std::string name = spec.substr(0, colon);
  std::vector<double> values;
  if (colon == std::string::npos || name == "vtk") return {name, values};
  std::stringstream in(spec.substr(colon + 1));
  std::string item;
  while (std::getline(in, item, ',')) {
    std::size_t used = 0;
    double v = NAN;
    try {
      v = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != item.size() || !std::isfinite(v))
      throw InputError("", "--flow", fmt::format("'{}' in '{}' is not a finite number", item, spec));
    values.push_back(v);
  }
  return {name, values};
}

Eigen::Vector3d vec3(const std::vector<double>& v, std::size_t at) { return {v[at], v[at + 1], v[at + 2]}; }

void need_counts(const std::string& spec, const std::vector<double>& v, std::initializer_list<std::size_t> counts) {
  for (std::size_t n : counts)
    if (v.size() == n) return;
  std::string allowed;
  for (std::size_t n : counts) allowed += (allowed.empty() ? "" : " or ") + std::to_string(n);
  throw InputError("", "--flow", fmt::format("'{}' has {} numbers; this flow takes {} ({})", spec, v.size(), allowed,
                                             kFlowHelp));
}

std::shared_ptr<const Flow> make_flow(const SimulateOptions& o, const CorrectionScene& cs, std::string* vtk_file) {
  const auto [name, v] = split_flow(o.flow);
  const Sheet& sheet = *cs.scene.sheet;
  try {
    if (name == "uniform") {
      need_counts(o.flow, v, {3});
      return std::make_shared<UniformFlow>(vec3(v, 0));
    }
    if (name == "rotation") {
      need_counts(o.flow, v, {1, 4, 7});
      return std::make_shared<SolidBodyRotationFlow>(v.size() == 7 ? vec3(v, 4) : sheet.origin_mm,
                                                     v.size() >= 4 ? vec3(v, 1) : sheet.normal(), v[0]);
    }
    if (name == "vortex") {
      need_counts(o.flow, v, {2, 3, 6});
      return std::make_shared<LambOseenVortexFlow>(v.size() == 6 ? vec3(v, 3) : sheet.origin_mm, sheet.normal(), v[0],
                                                   v[1], v.size() >= 3 ? v[2] : 0.0);
    }
    if (name == "poiseuille") {
      need_counts(o.flow, v, {2});
      return std::make_shared<PoiseuilleChannelFlow>(sheet.origin_mm, sheet.t_axis, sheet.s_axis, v[1], v[0]);
    }
    if (name == "stokes") {
      need_counts(o.flow, v, {4, 7});
      return std::make_shared<StokesSphereFlow>(v.size() == 7 ? vec3(v, 4) : sheet.origin_mm, v[0], vec3(v, 1));
    }
  } catch (const std::invalid_argument& e) {
    throw InputError("", "--flow", fmt::format("'{}': {}", o.flow, e.what()));
  }
  if (name == "vtk") {
    const std::string path = o.flow.size() > 4 ? o.flow.substr(4) : "";
    if (path.empty()) throw InputError("", "--flow", "vtk:FILE needs a file (.vti, .vtu or .vtk)");
    *vtk_file = path;
    VtkFlowOptions vo;
    vo.array = o.vtk_array;
    vo.mm_per_file_length = o.vtk_mm_per_length;
    const std::shared_ptr<const VtkFlow> f = read_vtk_flow(path, vo);
    check_covers_slab(*f, sheet, 3 * sheet.sigma_mm(), 0, SolidInteriors(cs.trace.solids));
    return f;
  }
  throw InputError("", "--flow", fmt::format("unknown flow '{}'; give one of {}", name, kFlowHelp));
}

// The sensor for a bit depth: the 12-bit defaults of sim/sensor.h scaled to the
// range, exposed so an in-plane particle peaks at peak_fraction of full scale.
SensorModel sensor_for(int bit_depth, double peak_fraction) {
  SensorModel s;
  s.bit_depth = bit_depth;
  const double scale = (1 << bit_depth) / 4096.0;
  s.gain_counts_per_electron = 0.5 * scale;
  s.background_counts = std::round(100 * scale);
  s.electrons_per_radiance = (peak_fraction * s.max_count() - s.background_counts) / s.gain_counts_per_electron;
  return s;
}

void check_options(const SimulateOptions& o) {
  auto positive = [](double v, const char* field, const char* what) {
    if (!(std::isfinite(v) && v > 0)) throw InputError("", field, fmt::format("{} must be positive ({})", number(v), what));
  };
  positive(o.dt_s, "--dt-s", "the pulse separation in s");
  positive(o.density_ppp, "--density-ppp", "tracers per pixel; the PIV rule is 0.02-0.05");
  positive(o.particle_px, "--particle-px", "the particle image diameter in px; 2-3 px is the rule");
  if (o.density_ppp > 1) throw InputError("", "--density-ppp", fmt::format("{} is over 1 tracer per pixel", number(o.density_ppp)));
  if (o.particle_px > 64) throw InputError("", "--particle-px", fmt::format("{} px is over 64 px", number(o.particle_px)));
  if (o.bit_depth != 8 && o.bit_depth != 12 && o.bit_depth != 16)
    throw InputError("", "--bit-depth", fmt::format("{} bits: give 8, 12 or 16", o.bit_depth));
  if (!(o.peak_fraction > 0 && o.peak_fraction <= 1))
    throw InputError("", "--peak-fraction", fmt::format("{} must lie in (0, 1]", number(o.peak_fraction)));
  if (o.binning < 1 || o.binning > 64) throw InputError("", "--binning", fmt::format("{} must be 1 to 64", o.binning));
  if (o.truth_window_px < 8 || o.truth_window_px > 4096)
    throw InputError("", "--truth-window", fmt::format("{} px must be 8 to 4096 px", o.truth_window_px));
  positive(o.vtk_mm_per_length, "--vtk-mm-per-length", "mm per file length unit");
}

// The option that sets a PivExperimentSettings field (ExperimentSettingError::setting).
std::string option_of_setting(const std::string& setting) {
  if (setting == "flow") return "--flow";
  if (setting == "dt_s") return "--dt-s";
  if (setting == "time_a_s") return "--time-a-s";
  if (setting == "density_ppp") return "--density-ppp";
  if (setting == "particle_px") return "--particle-px";
  if (setting == "peak_radiance") return "--peak-fraction";
  if (setting == "bit_depth") return "--bit-depth";
  return setting;
}

// The truth as a PIV vector field (piv/vector_file.h columns), flag 2 where it has none.
PivField truth_field(const InterrogationGrid& grid, const CameraTruth& t) {
  PivField f;
  f.grid = grid;
  f.u_px = t.u_px;
  f.v_px = t.v_px;
  f.flags.assign(t.u_px.size(), VectorFlag::valid);
  f.peak_ratio.assign(t.u_px.size(), 0.0);
  for (std::size_t i = 0; i < f.size(); ++i)
    if (!std::isfinite(f.u_px[i]) || !std::isfinite(f.v_px[i])) {
      f.flags[i] = VectorFlag::invalid;
      f.u_px[i] = f.v_px[i] = NAN;
    }
  return f;
}

std::string sheet_truth_text(const SheetTruth& st, const SheetPlane& plane) {
  std::string out = fmt::format(
      "# glasspiv simulate: true displacement on the rectified sheet grid (docs/simulation.md)\n"
      "# grid: {} x {} cells of {:.17g} mm; s = s0 + col * mm, t = t0 - row * mm (docs/correction.md)\n"
      "# s_axis: [{:.17g}, {:.17g}, {:.17g}], t_axis: [{:.17g}, {:.17g}, {:.17g}] (world)\n"
      "# ds_mm dt_mm: in-plane displacement of frame B relative to frame A; u_*: velocity at mid-pulse, m/s\n"
      "# flag: 0 valid, 2 inside a solid (nan)\n"
      "# s_mm t_mm ds_mm dt_mm u_s_m_per_s u_t_m_per_s u_n_m_per_s flag\n",
      st.grid.cols, st.grid.rows, st.grid.mm_per_px, plane.s_axis.x(), plane.s_axis.y(), plane.s_axis.z(),
      plane.t_axis.x(), plane.t_axis.y(), plane.t_axis.z());
  for (int r = 0; r < st.grid.rows; ++r)
    for (int c = 0; c < st.grid.cols; ++c) {
      const std::size_t i = static_cast<std::size_t>(r) * st.grid.cols + c;
      const bool ok = std::isfinite(st.ds_mm[i]);
      out += fmt::format("{} {} {} {} {} {} {} {}\n", st.grid.s_mm(c), st.grid.t_mm(r), st.ds_mm[i], st.dt_mm[i],
                         st.velocity_s_m_per_s[i], st.velocity_t_m_per_s[i], st.velocity_n_m_per_s[i], ok ? 0 : 2);
    }
  return out;
}

std::vector<float> normalised_counts(const cv::Mat& counts) {
  std::vector<float> v(counts.total());
  for (int r = 0; r < counts.rows; ++r)
    for (int c = 0; c < counts.cols; ++c)
      v[static_cast<std::size_t>(r) * counts.cols + c] = counts.at<std::uint16_t>(r, c) / 65535.0f;
  return v;
}

void run_simulate(const SimulateOptions& o) {
  check_options(o);
  CorrectionScene cs = read_correction_scene(o.scene);
  std::vector<int> indices;
  if (o.camera == "all") {
    for (std::size_t i = 0; i < cs.scene.cameras.size(); ++i) indices.push_back(static_cast<int>(i));
  } else {
    indices.push_back(find_camera(cs.scene, o.camera, "--camera"));
  }
  std::string vtk_file;
  const std::shared_ptr<const Flow> flow = make_flow(o, cs, &vtk_file);

  const fs::path dir(o.output);
  std::vector<std::string> inputs = scene_input_files(cs.scene);
  if (!vtk_file.empty()) inputs.push_back(vtk_file);
  std::vector<OutputFile> outputs = {{o.output, "-o", OutputKind::folder}};
  for (int ci : indices) {
    const std::string& n = cs.scene.cameras[static_cast<std::size_t>(ci)].name;
    for (const char* suffix : {"_A.tif", "_B.tif", "_A_ref.tif", "_B_ref.tif", "_truth_px.txt"})
      outputs.push_back({(dir / (n + suffix)).string(), "-o"});
  }
  outputs.push_back({(dir / "truth_sheet_mm.txt").string(), "-o"});
  outputs.push_back({(dir / "metadata.json").string(), "-o"});
  check_outputs(inputs, outputs);

  std::vector<ExperimentCamera> cameras;
  for (int ci : indices) {
    const SceneCamera& sc = cs.scene.cameras[static_cast<std::size_t>(ci)];
    cameras.push_back({sc.name, o.binning > 1 ? binned(sc.camera.model, o.binning) : sc.camera.model,
                       *sc.camera.camera_from_world});
  }
  PivExperimentSettings s;
  s.dt_s = o.dt_s;
  s.time_a_s = o.time_a_s;
  s.density_ppp = o.density_ppp;
  s.particle_px = o.particle_px;
  s.sensor = sensor_for(o.bit_depth, o.peak_fraction);
  s.seed = o.seed;
  s.threads = o.threads;
  // The truth on the final grid of a PIV evaluation with truth_window_px windows, 50 % overlap.
  PivOptions piv;
  piv.window_px = {o.truth_window_px};
  std::vector<InterrogationGrid> grids;
  for (const ExperimentCamera& c : cameras) {
    if (c.model.width_px() < o.truth_window_px || c.model.height_px() < o.truth_window_px)
      throw InputError("", "--truth-window", fmt::format("{} px windows do not fit in camera '{}' ({}x{} px)",
                                                         o.truth_window_px, c.name, c.model.width_px(),
                                                         c.model.height_px()));
    grids.push_back(final_piv_grid(c.model.width_px(), c.model.height_px(), piv));
  }
  for (const InterrogationGrid& g : grids) {
    PivExperimentSettings::TruthGrid t;
    for (int c = 0; c < g.cols; ++c) t.x_px.push_back(g.x_px(c));
    for (int r = 0; r < g.rows; ++r) t.y_px.push_back(g.y_px(r));
    s.truth_grids.push_back(std::move(t));
  }

  std::printf("scene %s: %zu camera%s, flow %s, dt %g s, %g tracers per px, %g px particles, %d-bit, seed %llu\n",
              o.scene.c_str(), cameras.size(), cameras.size() == 1 ? "" : "s", o.flow.c_str(), o.dt_s, o.density_ppp,
              o.particle_px, o.bit_depth, static_cast<unsigned long long>(o.seed));
  const Stopwatch clock;
  PivExperiment e;
  {
    ProgressBar bar("simulate", 1000);
    try {
      e = simulate_piv_experiment(cs.trace, *cs.scene.sheet, cameras, *flow, s, [&bar](double f) {
        bar.set_done(static_cast<std::size_t>(1000 * f));
      });
    } catch (const ExperimentSettingError& ex) {
      throw InputError("", option_of_setting(ex.setting()), ex.what());
    } catch (const std::invalid_argument& ex) {
      throw InputError(o.scene, "", ex.what());
    }
    bar.finish();
  }

  // Every file, written together or not at all.
  std::vector<AtomicFileWriter> writers;
  nlohmann::json cams = nlohmann::json::array();
  for (std::size_t k = 0; k < cameras.size(); ++k) {
    const ExperimentCameraResult& r = e.cameras[k];
    const std::pair<const char*, const cv::Mat*> frames[] = {
        {"_A.tif", &r.frame_a}, {"_B.tif", &r.frame_b}, {"_A_ref.tif", &r.frame_a_ref}, {"_B_ref.tif", &r.frame_b_ref}};
    for (const auto& [suffix, mat] : frames) {
      auto values = std::make_shared<std::vector<float>>(normalised_counts(*mat));
      const int w = r.width, h = r.height;
      writers.push_back({(dir / (r.name + suffix)).string(), [values, w, h](const std::string& tmp) {
                           write_gray_image(tmp, values->data(), w, h, PixelFormat::uint16);
                         }});
    }
    const std::string truth_text = vector_file_text(
        truth_field(grids[k], r.truth),
        {"glasspiv simulate: the TRUE displacement (sim/piv_experiment.h), not a measurement",
         fmt::format("camera '{}' with the glass removed ({} frames), {}x{} px", r.name, r.name + "_A_ref.tif", r.width,
                     r.height),
         "the tracer on the sheet plane at the window centre at mid-pulse, RK4 back and on by dt/2"});
    writers.push_back({(dir / (r.name + "_truth_px.txt")).string(),
                       [truth_text](const std::string& tmp) { write_file_atomically(tmp, truth_text); }});
    cams.push_back({{"name", r.name},
                    {"width_px", r.width},
                    {"height_px", r.height},
                    {"binning", o.binning},
                    {"mm_per_px_glass_removed", r.mm_per_px},
                    {"max_displacement_px", r.truth.max_displacement_px},
                    {"files",
                     {{"frame_a", r.name + "_A.tif"},
                      {"frame_b", r.name + "_B.tif"},
                      {"frame_a_ref", r.name + "_A_ref.tif"},
                      {"frame_b_ref", r.name + "_B_ref.tif"},
                      {"truth_px", r.name + "_truth_px.txt"}}}});
  }
  const std::string sheet_text = sheet_truth_text(e.sheet_truth, cs.trace.sheet);
  writers.push_back({(dir / "truth_sheet_mm.txt").string(),
                     [sheet_text](const std::string& tmp) { write_file_atomically(tmp, sheet_text); }});
  const SensorModel& sn = s.sensor;
  nlohmann::json meta = {
      {"glasspiv_simulate", 1},
      {"version", GLASSPIV_VERSION},
      {"scene", o.scene},
      {"flow", o.flow},
      {"vtk_array", o.vtk_array},
      {"vtk_mm_per_length", o.vtk_mm_per_length},
      {"seed", o.seed},
      {"dt_s", o.dt_s},
      {"time_a_s", o.time_a_s},
      {"density_ppp", o.density_ppp},
      {"tracers_per_mm3", e.tracers_per_mm3},
      {"tracers", e.tracers},
      {"particle_px", o.particle_px},
      {"particle_diameter_mm", e.particle_diameter_mm},
      {"peak_fraction", o.peak_fraction},
      {"rk4_sub_steps", s.rk4_sub_steps},
      {"texture_mm_per_texel", e.mm_per_texel},
      {"texture_texels_per_px", e.texels_per_px},
      {"trace", {{"reflections", s.trace.reflections}, {"min_weight", s.trace.min_weight}, {"max_depth", s.trace.max_depth}}},
      {"sensor",
       {{"bit_depth", sn.bit_depth},
        {"electrons_per_radiance", sn.electrons_per_radiance},
        {"gain_counts_per_electron", sn.gain_counts_per_electron},
        {"background_counts", sn.background_counts},
        {"read_noise_electrons", sn.read_noise_electrons},
        {"shot_noise", sn.shot_noise}}},
      {"tiff_levels", "raw counts in uint16 (a 12-bit frame holds 0-4095)"},
      {"truth_window_px", o.truth_window_px},
      {"truth_overlap", piv.overlap},
      {"max_displacement_px", e.max_displacement_px},
      {"approximation",
       "tracers drawn on the sheet plane at their (s, t), weighted by the sheet's Gaussian profile: the sheet is thin "
       "compared with the optics' depth of field"},
      {"warnings", e.warnings},
      {"cameras", cams}};
  const std::string meta_text = json_text(meta);
  writers.push_back({(dir / "metadata.json").string(),
                     [meta_text](const std::string& tmp) { write_file_atomically(tmp, meta_text); }});
  make_output_folder(dir.string(), "-o");
  write_files_atomically(writers);
  for (const std::string& w : e.warnings) std::fprintf(stderr, "glasspiv: warning: %s\n", w.c_str());
  std::printf("simulated %zu tracers (%.4g per mm^3), largest displacement %.3g px, in %.2f s; wrote %s\n", e.tracers,
              e.tracers_per_mm3, e.max_displacement_px, clock.seconds(), folder_shown(o.output).c_str());
}

}  // namespace

void register_simulate_command(CLI::App& app) {
  auto o = std::make_shared<SimulateOptions>();
  CLI::App* c = app.add_subcommand(
      "simulate",
      "A simulated PIV experiment with ground truth: per camera the frames A and B through the glass, the same with "
      "the glass removed, and the true displacement (docs/simulation.md)");
  c->add_option("scene", o->scene, "Scene file (docs/scene.md)")->required()->check(CLI::ExistingFile);
  c->add_option("--flow", o->flow, std::string("The flow: ") + kFlowHelp)->required();
  c->add_option("-o,--output", o->output,
                "Output folder: CAM_A.tif, CAM_B.tif, CAM_A_ref.tif, CAM_B_ref.tif, CAM_truth_px.txt, "
                "truth_sheet_mm.txt, metadata.json")
      ->required();
  c->add_option("--dt-s", o->dt_s, "Pulse separation in s")->capture_default_str();
  c->add_option("--time-a-s", o->time_a_s, "Time of frame A in s (for unsteady flows)")->capture_default_str();
  c->add_option("--density-ppp", o->density_ppp,
                "Tracers per pixel of the first camera's glass-removed view, in the sheet thickness (rule: 0.02-0.05)")
      ->capture_default_str();
  c->add_option("--particle-px", o->particle_px, "Particle image diameter (1/e^2) in px, glass removed (rule: 2-3)")
      ->capture_default_str();
  c->add_option("--bit-depth", o->bit_depth, "Sensor bits: 8, 12 or 16 (stored as counts in uint16 TIFF)")
      ->capture_default_str();
  c->add_option("--peak-fraction", o->peak_fraction, "An in-plane particle's peak as a fraction of full scale")
      ->capture_default_str();
  c->add_option("--seed", o->seed, "Seed of the tracers and of every frame's noise")->capture_default_str();
  c->add_option("--camera", o->camera, "A camera of the scene, or all")->capture_default_str();
  c->add_option("--binning", o->binning, "Cameras read out K x K binned (quick experiments)")->capture_default_str();
  c->add_option("--truth-window", o->truth_window_px,
                "Window of the PIV grid the truth is sampled on, px (50 % overlap)")
      ->capture_default_str();
  c->add_option("--vtk-array", o->vtk_array, "vtk:FILE: the velocity array (default: U, velocity, Velocity or the only one)");
  c->add_option("--vtk-mm-per-length", o->vtk_mm_per_length, "vtk:FILE: mm per file length unit (1000: metres)")
      ->capture_default_str();
  c->add_option("--threads", o->threads, "Threads (default: all cores)")->check(CLI::NonNegativeNumber);
  c->callback([o]() { run_simulate(*o); });
}

}  // namespace glasspiv
