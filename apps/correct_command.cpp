// glasspiv correct: distorted PIV frames made undistorted through the scene's
// calibrated model (one camera onto its own grid with the glass removed or
// onto the rectified sheet grid; several cameras onto the sheet grid), and
// glasspiv coverage: which parts of the sheet a set of cameras can reconstruct.
#include <glob.h>
#include <sys/stat.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <set>

#include <fmt/format.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "apps/cli_checks.h"
#include "apps/cli_files.h"
#include "apps/commands.h"
#include "apps/correction_setup.h"
#include "apps/photo_detection.h"
#include "correct/back_projector.h"
#include "correct/frame_provenance.h"
#include "correct/reconstruct.h"
#include "correct/series.h"
#include "util/atomic_file.h"
#include "util/image_file.h"
#include "util/input_error.h"
#include "util/progress_bar.h"
#include "util/stopwatch.h"

namespace glasspiv {
namespace {
namespace fs = std::filesystem;

struct CorrectOptions {
  std::string scene, camera, output, grid = "camera", method = "accumulate", format = "16", cache_dir, shard;
  std::vector<std::string> images, frames, camera_weights;
  double mm_per_px = 0, smoothness = LeastSquaresOptions{}.smoothness;
  double min_pixels = MaskOptions{}.min_pixels_per_cell, min_weight = MaskOptions{}.min_mean_weight;
  double trace_min_weight = correction_trace_options().min_weight;
  int max_iterations = LeastSquaresOptions{}.max_iterations, samples = 1, threads = 0, binning = 1;
  bool no_reflections = false, no_cache = false, prepare_only = false;
};

CorrectionSettings settings(const CorrectOptions& o, const std::string& default_cache) {
  CorrectionSettings s;
  s.trace.min_weight = o.trace_min_weight;
  s.trace.reflections = !o.no_reflections;
  s.samples = o.samples;
  s.mask.min_pixels_per_cell = o.min_pixels;
  s.mask.min_mean_weight = o.min_weight;
  s.binning = o.binning;
  s.threads = o.threads;
  s.cache_dir = o.no_cache ? "" : (!o.cache_dir.empty() ? o.cache_dir : default_cache);
  return s;
}

LeastSquaresOptions least_squares_options(const CorrectOptions& o) {
  LeastSquaresOptions lsq;
  lsq.smoothness = o.smoothness;
  lsq.max_iterations = o.max_iterations;
  return lsq;
}

// Least squares on one frame, its refusal (no finite pixel, overflow) named by the frame.
std::vector<float> least_squares_of_frame(const std::vector<CameraImage>& views, const std::vector<CellState>& states,
                                          const std::vector<float>& start, const LeastSquaresOptions& lsq,
                                          const std::string& frame, LeastSquaresReport* report = nullptr) {
  try {
    return least_squares(views, states, start, lsq, report);
  } catch (const std::invalid_argument& e) {
    throw InputError(frame, "--method lsq", e.what());
  }
}

SheetGrid grid_for(const CorrectionScene& cs, double mm_per_px) {
  // The limit stated here, before any work and with readable numbers.
  const double es = cs.trace.sheet.extent_s_mm, et = cs.trace.sheet.extent_t_mm;
  const double cells = std::ceil(es / mm_per_px) * std::ceil(et / mm_per_px);
  if (!(mm_per_px > 0) || !(cells <= static_cast<double>(kMaxSheetGridCells)))
    throw InputError("", "--mm-per-px",
                     fmt::format("{} mm makes a grid of {} cells over the {} x {} mm sheet; the limit is {} cells "
                                 "(give about {} mm or more)",
                                 number(mm_per_px), number(cells), number(es), number(et),
                                 number(static_cast<double>(kMaxSheetGridCells)),
                                 number(std::sqrt(es * et / static_cast<double>(kMaxSheetGridCells)) * 1.001)));
  try {
    return sheet_grid_covering(cs.trace.sheet, mm_per_px);
  } catch (const std::invalid_argument& e) {
    throw InputError("", "--mm-per-px", e.what());
  }
}

// "K/N" with 0 <= K < N.
std::pair<int, int> parse_shard(const std::string& text) {
  const std::size_t slash = text.find('/');
  if (slash == std::string::npos || text.find('/', slash + 1) != std::string::npos)
    throw InputError("", "--shard", fmt::format("'{}' is not K/N with 0 <= K < N (e.g. 0/4 .. 3/4)", text));
  // Each number within int, never wrapped: 4294967296/2 is not 0/2.
  const std::string_view all(text);
  const int n = option_integer<int>("--shard", text, all.substr(slash + 1), 1, INT_MAX);
  const int k = option_integer<int>("--shard", text, all.substr(0, slash), 0, INT_MAX);
  if (k >= n) throw InputError("", "--shard", fmt::format("'{}' is not K/N with 0 <= K < N (e.g. 0/4 .. 3/4)", text));
  return {k, n};
}

// Files, folders of images (sorted) or glob patterns.
std::vector<std::string> expand_frames(const std::string& spec) {
  std::error_code ec;
  if (spec.find_first_of("*?[") != std::string::npos && !fs::exists(spec, ec)) {
    glob_t g{};
    std::vector<std::string> out;
    if (::glob(spec.c_str(), 0, nullptr, &g) == 0)
      for (std::size_t i = 0; i < g.gl_pathc; ++i) out.emplace_back(g.gl_pathv[i]);
    ::globfree(&g);
    if (out.empty()) throw InputError(spec, "", "the pattern matches no file");
    return out;  // glob sorts
  }
  return expand_photo_inputs({spec});
}

PixelFormat output_format(const std::string& name) {
  const PixelFormat f = pixel_format_from_name(name, "--format");
  return f;
}

void check_frame_size(const GrayImage& img, const std::string& path, const CorrectionCamera& cam) {
  if (img.width != cam.model.width_px() || img.height != cam.model.height_px())
    throw InputError(path, "image size",
                     fmt::format("{}x{} px, but camera '{}' records {}x{} px", img.width, img.height, cam.name,
                                 cam.model.width_px(), cam.model.height_px()));
}

// Every frame's header before any tracing: a wrong size or an unreadable file is
// reported at once, not after minutes of work.
void check_frame_headers(const std::vector<std::string>& paths, const CorrectionScene& cs, int camera_index, int binning) {
  const SceneCamera& sc = cs.scene.cameras[static_cast<std::size_t>(camera_index)];
  const CameraModel model = binning > 1 ? binned(sc.camera.model, binning) : sc.camera.model;
  for (const std::string& path : paths) {
    const auto header = read_image_file_header(path);
    if (!header) read_gray_image(path);  // throws the reader's one-line error
    const int w = header ? header->width : 0, h = header ? header->height : 0;
    if (!header || w != model.width_px() || h != model.height_px())
      throw InputError(path, "image size",
                       fmt::format("{}x{} px, but camera '{}' records {}x{} px{}", w, h, sc.name, model.width_px(),
                                   model.height_px(), binning > 1 ? fmt::format(" (binned {}x{})", binning, binning) : ""));
    // Other integer types are rescaled by the reader (counts / their maximum): the frame's scale would be lost.
    const std::string& type = header->sample_type;
    if (type != "uint8" && type != "uint16" && type != "half" && type != "float" && type != "double")
      throw InputError(path, "",
                       fmt::format("{} pixels: glasspiv correct reads 8- or 16-bit or float frames, whose scale it "
                                   "keeps (convert the frames, e.g. to float TIFF)",
                                   type));
  }
}

// A float frame is written as 16 bits only when it lies in [0, 1], the scale of
// 16-bit files (0..65535): counts would saturate.
void check_sixteen_bit_scale(const GrayImage& img, const std::string& path, PixelFormat format) {
  if (format != PixelFormat::uint16 || img.source_format != PixelFormat::float32) return;
  float lo = 0, hi = 0;
  bool any = false;
  for (float v : img.values)
    if (std::isfinite(v)) {
      lo = any ? std::min(lo, v) : v;
      hi = any ? std::max(hi, v) : v;
      any = true;
    }
  if (any && (lo < 0 || hi > 1))
    throw InputError(path, "--format",
                     fmt::format("float pixels from {} to {}, but 16-bit output holds 0 to 1 (as 0 to 65535) and would "
                                 "clip them: give --format float to keep the frames' scale",
                                 number(lo), number(hi)));
}

// Non-finite pixels of a frame are left out of the reconstruction (correct/reconstruct.h);
// a frame with none finite has nothing to correct.
std::size_t check_finite(const GrayImage& img, const std::string& path) {
  const std::size_t bad = count_non_finite(img.values.data(), img.values.size());
  if (bad == img.values.size())
    throw InputError(path, "", "no pixel is finite (all NaN or infinite): nothing to correct");
  return bad;
}

std::vector<float> mask_values(const std::vector<CellState>& states) {
  std::vector<float> v(states.size());
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = states[i] == CellState::valid ? 1.0f : 0.0f;
  return v;
}

void write_grid_placement(const std::string& path, const SheetGrid& g, const CorrectionScene& cs) {
  write_file_atomically(path, sheet_grid_yaml(g, cs.trace.sheet, cs.scene.source));
}

void print_coverage(const CellCounts& n, const char* what) {
  std::printf("%s: %.2f%% of the sheet's fluid region valid (%zu cells; masked: %zu never seen, %zu too few pixels, "
              "%zu mostly reflected, %zu too little weight; %zu inside solids)\n",
              what, 100 * n.valid_fraction_of_fluid(), n.valid, n.never_seen, n.few_pixels, n.mostly_reflected,
              n.low_weight, n.inside_solid);
}

// Output names: DIR/<input stem>.tif, distinct (check_outputs then checks them against the inputs).
std::vector<std::string> output_names(const std::vector<std::string>& inputs, const std::string& dir) {
  std::vector<std::string> out;
  std::set<std::string> seen;
  for (const std::string& in : inputs) {
    const std::string name = (fs::path(dir) / (fs::path(in).stem().string() + ".tif")).string();
    std::error_code ec;
    const fs::path canonical = fs::weakly_canonical(name, ec);
    if (!seen.insert((ec ? fs::path(name).lexically_normal() : canonical).string()).second)
      throw InputError(in, "", "two frames would be written to the same output " + name + " (rename one)");
    out.push_back(name);
  }
  return out;
}

struct Frame {
  std::vector<GrayImage> images;  // per camera
  std::vector<float> result;
};

// An input frame's identity in a provenance record: name, bytes, modification time.
std::string input_identity(const std::string& path) {
  struct stat st{};
  if (::stat(path.c_str(), &st) != 0) throw InputError(path, "", "cannot read the file's status");
  return fmt::format("{}, {} bytes, modified {}.{:09d}", fs::path(path).filename().string(),
                     static_cast<long long>(st.st_size), static_cast<long long>(st.st_mtim.tv_sec),
                     static_cast<long>(st.st_mtim.tv_nsec));
}

std::string fingerprint_text(std::uint64_t fp) { return fmt::format("{:016x}", fp); }

// The setup part of every frame's record: what changes the pixels of a series
// (numbers in their shortest form that reads back exactly).
std::map<std::string, std::string> series_setup(const CorrectOptions& o, const CorrectionScene& cs, const SheetGrid& grid,
                                                PixelFormat format, const std::vector<double>& weights) {
  std::map<std::string, std::string> setup;
  for (std::size_t k = 0; k < cs.cameras.size(); ++k) {
    setup["operator " + cs.cameras[k].name] = fingerprint_text(cs.cameras[k].op_fingerprint);
    setup["weight " + cs.cameras[k].name] = fmt::format("{}", weights.empty() ? 1.0 : weights[k]);
  }
  setup["method"] = o.method;
  if (o.method == "lsq") {
    const LeastSquaresOptions lsq = least_squares_options(o);
    setup["smoothness"] = fmt::format("{}", lsq.smoothness);
    setup["max iterations"] = std::to_string(lsq.max_iterations);
    setup["tolerance"] = fmt::format("{}", lsq.tolerance);
  }
  setup["grid"] = o.grid;
  setup["sheet grid"] = fmt::format("{}x{} cells of {} mm, cell (0, 0) at s {}, t {}", grid.cols, grid.rows,
                                    grid.mm_per_px, grid.s0_mm, grid.t0_mm);
  setup["format"] = pixel_format_name(format);
  setup["min pixels"] = fmt::format("{}", o.min_pixels);
  setup["min weight"] = fmt::format("{}", o.min_weight);
  setup["background radiance"] = fmt::format("{}", cs.scene.background.radiance);
  return setup;
}

// Which outputs of a series are kept on a rerun: those whose record is the one
// this run would write, complete and of the right size. Every other existing
// output is redone, and why is counted.
struct SeriesRecords {
  std::vector<char> keep;           // per frame index
  std::vector<std::string> record;  // per frame index to do: the text written into it
  std::map<std::string, std::size_t> redo;
  std::size_t redone() const {
    std::size_t n = 0;
    for (const auto& r : redo) n += r.second;
    return n;
  }
  std::string why() const {
    std::string text;
    for (const auto& [reason, n] : redo) text += fmt::format("{}{} {}", text.empty() ? "" : "; ", n, reason);
    return text;
  }
};

// inputs(i): per camera name, the input file of frame i.
SeriesRecords check_series(const std::vector<std::size_t>& frames, const std::vector<std::string>& outputs, int width,
                           int height, const std::map<std::string, std::string>& setup,
                           const std::function<std::map<std::string, std::string>(std::size_t)>& inputs) {
  SeriesRecords sr;
  sr.keep.assign(outputs.size(), 0);
  sr.record.resize(outputs.size());
  for (std::size_t i : frames) {
    FrameProvenance wanted{setup, {}};
    for (const auto& [camera, path] : inputs(i)) wanted.inputs[camera] = input_identity(path);
    sr.record[i] = provenance_text(wanted);
    std::error_code ec;
    if (!fs::exists(fs::symlink_status(outputs[i], ec))) continue;  // not written yet
    const auto header = read_image_file_header(outputs[i], true);
    std::string why;
    if (!header || !header->pixels_present) why = "incomplete or unreadable";
    else if (header->width != width || header->height != height) why = "of another size";
    else if (header->description != sr.record[i]) why = provenance_difference(header->description, wanted);
    if (why.empty()) sr.keep[i] = 1;
    else ++sr.redo[why];
  }
  if (sr.redone()) std::printf("redoing %s written before: %s\n", count_of(sr.redone(), "frame").c_str(), sr.why().c_str());
  return sr;
}

// What a series left out: non-finite input pixels, and the valid cells they leave without data.
struct LeftOut {
  std::size_t pixels = 0, frames = 0, cells = 0;
  std::string text(PixelFormat format) const {
    if (!pixels) return "";
    return fmt::format("; left out {} not finite in {}{}", count_of(pixels, "pixel"), count_of(frames, "frame"),
                       cells ? fmt::format(" ({} without data: {})", count_of(cells, "cell"),
                                           format == PixelFormat::float32 ? "NaN" : "0")
                             : "");
  }
};

void run_one_camera(const CorrectOptions& o) {
  const PixelFormat format = output_format(o.format);
  if (format == PixelFormat::uint8) throw InputError("", "--format", "write 16 or float (8 bits lose the corrected levels)");
  const std::vector<std::string> inputs = expand_photo_inputs(o.images);
  CorrectionScene cs = read_correction_scene(o.scene);
  const CorrectionSettings s = settings(o, (fs::path(o.output) / "cache").string());
  const std::vector<std::string> outputs = output_names(inputs, o.output);
  const int ci = find_camera(cs.scene, o.camera, "--camera");
  // Every output against every input (the scene's files included), before any work.
  std::vector<std::string> all_inputs = scene_input_files(cs.scene);
  all_inputs.insert(all_inputs.end(), inputs.begin(), inputs.end());
  std::vector<OutputFile> all_outputs = {{o.output, "-o", OutputKind::folder}};
  for (const std::string& out : outputs) all_outputs.push_back({out, "-o"});
  all_outputs.push_back({(fs::path(o.output) / "mask.tif").string(), "-o"});
  if (o.grid == "sheet") all_outputs.push_back({(fs::path(o.output) / "sheet_grid.yaml").string(), "-o"});
  if (!s.cache_dir.empty()) all_outputs.push_back({correction_cache_files(cs.scene, ci, s).map, "--cache-dir", OutputKind::transport_map});
  check_outputs(all_inputs, all_outputs);
  if (o.mm_per_px > 0) grid_for(cs, o.mm_per_px);
  std::vector<std::size_t> frames(inputs.size());
  for (std::size_t i = 0; i < frames.size(); ++i) frames[i] = i;
  if (!o.shard.empty()) {
    const auto [k, n] = parse_shard(o.shard);
    frames = shard_frames(inputs.size(), k, n);
  }
  if (o.prepare_only) frames.clear();
  check_frame_headers(inputs, cs, ci, o.binning);
  make_output_folder(o.output, "-o");

  const GlassRemovedView direct = glass_removed_view(cs, ci, s);
  const SheetGrid grid = grid_for(cs, o.mm_per_px > 0 ? o.mm_per_px : direct.footprint_mm);
  if (!s.cache_dir.empty()) {
    all_outputs.push_back({correction_cache_files(cs.scene, ci, s, grid.cols, grid.rows).op, "--cache-dir", OutputKind::correction_operator});
    check_outputs(all_inputs, all_outputs);
  }
  std::printf("scene %s: camera '%s'; sheet grid %dx%d cells of %.4g mm%s\n", o.scene.c_str(),
              cs.scene.cameras[static_cast<std::size_t>(ci)].name.c_str(), grid.cols, grid.rows, grid.mm_per_px,
              o.mm_per_px > 0 ? "" : " (the camera's own pixel on the sheet)");
  add_correction_camera(cs, ci, grid, s);
  const CorrectionCamera& cam = cs.cameras.front();
  const std::vector<CellState> states = classify_cells(camera_operators(cs), cs.trace, s.mask);
  print_coverage(count_cells(states), ("camera '" + cam.name + "'").c_str());

  const bool on_camera = o.grid == "camera";
  CameraResampler resampler;
  int out_w = grid.cols, out_h = grid.rows;
  if (on_camera) {
    resampler = make_camera_resampler(build_correction_operator(direct.map, grid, s.op, s.threads), states);
    out_w = cam.model.width_px();
    out_h = cam.model.height_px();
    std::size_t valid = 0;
    for (std::uint8_t v : resampler.pixel_valid) valid += v != 0;
    std::printf("camera grid (glass removed): %.2f%% of the pixels valid\n", 100.0 * valid / resampler.pixel_valid.size());
    std::vector<float> m(resampler.pixel_valid.begin(), resampler.pixel_valid.end());
    for (float& v : m) v /= 255;
    write_gray_image((fs::path(o.output) / "mask.tif").string(), m.data(), out_w, out_h, PixelFormat::uint8);
  } else {
    const std::vector<float> m = mask_values(states);
    write_gray_image((fs::path(o.output) / "mask.tif").string(), m.data(), out_w, out_h, PixelFormat::uint8);
    write_grid_placement((fs::path(o.output) / "sheet_grid.yaml").string(), grid, cs);
  }

  const LeastSquaresOptions lsq = least_squares_options(o);
  const bool least = o.method == "lsq";
  const double background = cs.scene.background.radiance;
  // Back-projection prepared once: only the cells the output reads, already normalised.
  const bool prepared = !least && background == 0;
  std::vector<std::uint8_t> read_cells;
  if (prepared && on_camera) read_cells = cells_read_by(resampler, grid.cell_count());
  const BackProjector projector =
      prepared ? make_back_projector(camera_operators(cs), states, on_camera ? &read_cells : nullptr) : BackProjector{};
  const SeriesRecords records =
      check_series(frames, outputs, out_w, out_h, series_setup(o, cs, grid, format, {}),
                   [&](std::size_t i) { return std::map<std::string, std::string>{{cam.name, inputs[i]}}; });
  LeftOut left_out;
  ProgressBar bar("correct", frames.size(), "frames");
  const SeriesStats st = run_series<Frame>(
      frames, [&](std::size_t i) { return records.keep[i] != 0; },
      [&](std::size_t i) {
        Frame f;
        f.images.push_back(read_gray_image(inputs[i]));
        check_frame_size(f.images[0], inputs[i], cam);
        check_sixteen_bit_scale(f.images[0], inputs[i], format);
        return f;
      },
      [&](std::size_t i, Frame& f) {
        const std::vector<CameraImage> views = {{&cam.op, f.images[0].values.data(), 1.0, background}};
        const std::size_t non_finite = check_finite(f.images[0], inputs[i]);
        std::vector<float> l;
        if (prepared && non_finite == 0) {
          l.assign(grid.cell_count(), 0.0f);
          apply_back_projector(projector, f.images[0].values.data(), l.data());
        } else {
          l = back_projection(views, states);  // leaves the non-finite pixels out
        }
        if (least) l = least_squares_of_frame(views, states, l, lsq, inputs[i]);
        if (non_finite) {
          left_out.pixels += non_finite;
          ++left_out.frames;
          for (std::size_t c = 0; c < l.size(); ++c) left_out.cells += states[c] == CellState::valid && std::isnan(l[c]);
        }
        if (on_camera) {
          f.result.resize(static_cast<std::size_t>(out_w) * out_h);
          resample_to_camera(resampler, l.data(), f.result.data());
        } else {
          f.result = std::move(l);
        }
      },
      [&](std::size_t i, const Frame& f) {
        write_gray_image(outputs[i], f.result.data(), out_w, out_h, format, records.record[i]);
      },
      [&](std::size_t done, std::size_t) { bar.set_done(done); });
  bar.finish();
  std::printf("corrected %s in %.2f s (%.1f frames/s, %s, %s grid %dx%d)%s%s%s; wrote %s\n",
              count_of(st.corrected, "frame").c_str(),
              st.seconds, st.corrected / std::max(1e-9, st.seconds), least ? "least squares" : "back-projection",
              on_camera ? "camera" : "sheet", out_w, out_h,
              records.redone() ? fmt::format("; redid {} written before", records.redone()).c_str() : "",
              st.skipped ? fmt::format("; {} already done, skipped", st.skipped).c_str() : "",
              left_out.text(format).c_str(), folder_shown(o.output).c_str());
}

void run_several_cameras(const CorrectOptions& o) {
  const PixelFormat format = output_format(o.format);
  if (format == PixelFormat::uint8) throw InputError("", "--format", "write 16 or float (8 bits lose the corrected levels)");
  if (!o.images.empty()) throw InputError("", "--frame", "give frames either as --frame CAMERA=FILES or as IMAGES with --camera, not both");
  if (o.grid != "sheet")
    throw InputError("", "--grid", "--frame combines cameras on the sheet grid; for one camera's own grid give IMAGES and --camera");
  CorrectionScene cs = read_correction_scene(o.scene);
  // CAMERA=FILES, one camera each.
  std::vector<std::pair<int, std::vector<std::string>>> per_camera;
  std::set<int> used;
  for (const std::string& f : o.frames) {
    const auto eq = f.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == f.size())
      throw InputError("", "--frame", fmt::format("'{}' is not CAMERA=FILE (or =FOLDER, =PATTERN)", f));
    const int ci = find_camera(cs.scene, f.substr(0, eq), "--frame");
    if (!used.insert(ci).second) throw InputError("", "--frame", "camera '" + f.substr(0, eq) + "' given twice");
    per_camera.emplace_back(ci, expand_frames(f.substr(eq + 1)));
  }
  // --camera-weight CAMERA=W: that camera's share in the sums (checked before any tracing).
  std::map<std::string, double> weights;
  for (const std::string& cw : o.camera_weights) {
    const auto eq = cw.find('=');
    double w = -1;
    std::size_t used_chars = 0;
    try {
      if (eq != std::string::npos) w = std::stod(cw.substr(eq + 1), &used_chars);
    } catch (const std::exception&) {
      w = -1;
    }
    if (eq == std::string::npos || used_chars != cw.size() - eq - 1 || !(w >= 0) || !std::isfinite(w))
      throw InputError("", "--camera-weight", fmt::format("'{}' is not CAMERA=W with W >= 0", cw));
    bool found = false;
    for (const auto& pc : per_camera) found = found || cs.scene.cameras[static_cast<std::size_t>(pc.first)].name == cw.substr(0, eq);
    if (!found) throw InputError("", "--camera-weight", "camera '" + cw.substr(0, eq) + "' has no --frame");
    weights[cw.substr(0, eq)] = w;
  }
  const std::size_t count = per_camera.front().second.size();
  for (const auto& [ci, files] : per_camera)
    if (files.size() != count)
      throw InputError("", "--frame",
                       fmt::format("camera '{}' has {} frames but camera '{}' has {}: frames are matched by index",
                                   cs.scene.cameras[static_cast<std::size_t>(ci)].name, files.size(),
                                   cs.scene.cameras[static_cast<std::size_t>(per_camera.front().first)].name, count));
  const bool single_file = count == 1 && (lower_extension(o.output) == ".tif" || lower_extension(o.output) == ".tiff");
  const std::string dir = single_file ? fs::path(o.output).parent_path().string() : o.output;
  const CorrectionSettings s = settings(o, ((dir.empty() ? fs::path(".") : fs::path(dir)) / "glasspiv-cache").string());
  std::vector<std::string> all_inputs = scene_input_files(cs.scene);
  for (const auto& pc : per_camera) all_inputs.insert(all_inputs.end(), pc.second.begin(), pc.second.end());
  const std::vector<std::string> outputs =
      single_file ? std::vector<std::string>{o.output} : output_names(per_camera.front().second, o.output);
  const std::string stem = single_file ? (fs::path(dir) / fs::path(o.output).stem()).string() + "_" : (fs::path(dir) / "").string();
  const std::string mask_path = stem + "mask.tif", coverage_path = stem + "coverage.tif";
  // Every output against every input (the scene's files included), before any work.
  std::vector<OutputFile> all_outputs;
  for (const std::string& out : outputs) all_outputs.push_back({out, "-o"});
  for (const std::string& side : {mask_path, coverage_path, stem + "sheet_grid.yaml"}) all_outputs.push_back({side, "-o"});
  if (!s.cache_dir.empty())
    for (const auto& pc : per_camera) all_outputs.push_back({correction_cache_files(cs.scene, pc.first, s).map, "--cache-dir", OutputKind::transport_map});
  check_outputs(all_inputs, all_outputs);
  if (o.mm_per_px > 0) grid_for(cs, o.mm_per_px);
  std::vector<std::size_t> frames(count);
  for (std::size_t i = 0; i < count; ++i) frames[i] = i;
  if (!o.shard.empty()) {
    const auto [k, n] = parse_shard(o.shard);
    frames = shard_frames(count, k, n);
  }
  if (o.prepare_only) frames.clear();
  for (const auto& [ci, files] : per_camera) check_frame_headers(files, cs, ci, o.binning);
  make_output_folder(dir, "-o");

  const GlassRemovedView direct = glass_removed_view(cs, per_camera.front().first, s);
  const SheetGrid grid = grid_for(cs, o.mm_per_px > 0 ? o.mm_per_px : direct.footprint_mm);
  if (!s.cache_dir.empty()) {
    for (const auto& pc : per_camera)
      all_outputs.push_back({correction_cache_files(cs.scene, pc.first, s, grid.cols, grid.rows).op, "--cache-dir", OutputKind::correction_operator});
    check_outputs(all_inputs, all_outputs);
  }
  std::printf("scene %s: %s, %s each; sheet grid %dx%d cells of %.4g mm\n", o.scene.c_str(),
              count_of(per_camera.size(), "camera").c_str(), count_of(count, "frame").c_str(), grid.cols, grid.rows,
              grid.mm_per_px);
  for (const auto& pc : per_camera) add_correction_camera(cs, pc.first, grid, s);
  std::vector<CameraOperator> ops = camera_operators(cs);
  std::vector<double> camera_weights;
  for (std::size_t k = 0; k < cs.cameras.size(); ++k) {
    if (weights.count(cs.cameras[k].name)) ops[k].weight = weights.at(cs.cameras[k].name);
    camera_weights.push_back(ops[k].weight);
  }
  const std::vector<CellState> states = classify_cells(ops, cs.trace, s.mask);
  // Coverage count: cameras that could reconstruct each cell alone.
  std::vector<float> coverage(grid.cell_count(), 0.0f);
  for (std::size_t k = 0; k < ops.size(); ++k) {
    const std::vector<CellState> own = classify_cells({{ops[k].op, 1.0}}, cs.trace, s.mask);
    print_coverage(count_cells(own), ("camera '" + cs.cameras[k].name + "'").c_str());
    for (std::size_t c = 0; c < own.size(); ++c) coverage[c] += own[c] == CellState::valid ? 1.0f / 255 : 0.0f;
  }
  print_coverage(count_cells(states), "together");
  const std::vector<float> m = mask_values(states);
  write_gray_image(mask_path, m.data(), grid.cols, grid.rows, PixelFormat::uint8);
  write_gray_image(coverage_path, coverage.data(), grid.cols, grid.rows, PixelFormat::uint8);
  write_grid_placement(stem + "sheet_grid.yaml", grid, cs);

  const LeastSquaresOptions lsq = least_squares_options(o);
  const bool least = o.method == "lsq";
  const double background = cs.scene.background.radiance;
  const bool prepared = !least && background == 0;
  const BackProjector projector = prepared ? make_back_projector(ops, states) : BackProjector{};
  const SeriesRecords records =
      check_series(frames, outputs, grid.cols, grid.rows, series_setup(o, cs, grid, format, camera_weights),
                   [&](std::size_t i) {
                     std::map<std::string, std::string> in;
                     for (std::size_t k = 0; k < per_camera.size(); ++k) in[cs.cameras[k].name] = per_camera[k].second[i];
                     return in;
                   });
  LeftOut left_out;
  ProgressBar bar("correct", frames.size(), "frames");
  int iterations = 0;
  const SeriesStats st = run_series<Frame>(
      frames, [&](std::size_t i) { return records.keep[i] != 0; },
      [&](std::size_t i) {
        Frame f;
        for (std::size_t k = 0; k < per_camera.size(); ++k) {
          const std::string& path = per_camera[k].second[i];
          f.images.push_back(read_gray_image(path));
          check_frame_size(f.images.back(), path, cs.cameras[k]);
          check_sixteen_bit_scale(f.images.back(), path, format);
        }
        return f;
      },
      [&](std::size_t i, Frame& f) {
        std::size_t non_finite = 0;
        for (std::size_t k = 0; k < f.images.size(); ++k) non_finite += check_finite(f.images[k], per_camera[k].second[i]);
        if (non_finite) {
          left_out.pixels += non_finite;
          ++left_out.frames;
        }
        if (prepared && non_finite == 0) {
          std::vector<float> frame;
          frame.reserve(projector.frame_pixels);
          for (const GrayImage& im : f.images) frame.insert(frame.end(), im.values.begin(), im.values.end());
          f.result.assign(grid.cell_count(), 0.0f);
          apply_back_projector(projector, frame.data(), f.result.data());
          return;
        }
        std::vector<CameraImage> views;
        for (std::size_t k = 0; k < cs.cameras.size(); ++k)
          views.push_back({&cs.cameras[k].op, f.images[k].values.data(), ops[k].weight, background});
        f.result = back_projection(views, states);  // leaves the non-finite pixels out
        if (least) {
          LeastSquaresReport rep;
          f.result = least_squares_of_frame(views, states, f.result, lsq, per_camera.front().second[i], &rep);
          iterations += rep.iterations;
        }
        if (non_finite)
          for (std::size_t c = 0; c < f.result.size(); ++c)
            left_out.cells += states[c] == CellState::valid && std::isnan(f.result[c]);
      },
      [&](std::size_t i, const Frame& f) {
        write_gray_image(outputs[i], f.result.data(), grid.cols, grid.rows, format, records.record[i]);
      },
      [&](std::size_t done, std::size_t) { bar.set_done(done); });
  bar.finish();
  std::printf("corrected %s in %.2f s (%.2f per s, %s%s)%s%s%s; mask %s, coverage count %s\n",
              count_of(st.corrected, "instant").c_str(),
              st.seconds, st.corrected / std::max(1e-9, st.seconds), least ? "least squares" : "accumulation",
              least && st.corrected ? fmt::format(", {:.0f} iterations each", double(iterations) / st.corrected).c_str() : "",
              records.redone() ? fmt::format("; redid {} written before", records.redone()).c_str() : "",
              st.skipped ? fmt::format("; {} already done, skipped", st.skipped).c_str() : "",
              left_out.text(format).c_str(), mask_path.c_str(), coverage_path.c_str());
}

void run_correct(const CorrectOptions& o) {
  if (!o.frames.empty()) return run_several_cameras(o);
  if (o.images.empty()) throw InputError("", "IMAGES", "give the frames to correct (files or folders), or --frame CAMERA=FILES");
  if (lower_extension(o.output) == ".tif" || lower_extension(o.output) == ".tiff")
    throw InputError(o.output, "-o", "one camera writes a folder (one corrected image per frame, and mask.tif)");
  run_one_camera(o);
}

// glasspiv coverage
struct CoverageOptions {
  std::string scene, output, cache_dir;
  std::vector<std::string> cameras;
  double mm_per_px = 0, min_pixels = MaskOptions{}.min_pixels_per_cell, min_weight = MaskOptions{}.min_mean_weight;
  int binning = 1, threads = 0;
  bool no_reflections = false;
};

void run_coverage(const CoverageOptions& o) {
  if (lower_extension(o.output) != ".png") throw InputError(o.output, "-o", "must end in .png");
  CorrectionScene cs = read_correction_scene(o.scene);
  std::vector<int> indices;
  if (o.cameras.empty())
    for (std::size_t i = 0; i < cs.scene.cameras.size(); ++i) indices.push_back(static_cast<int>(i));
  for (const std::string& name : o.cameras) {
    const int ci = find_camera(cs.scene, name, "--camera");
    if (std::find(indices.begin(), indices.end(), ci) != indices.end())
      throw InputError("", "--camera", "camera '" + name + "' is given twice (name each camera once)");
    indices.push_back(ci);
  }
  CorrectOptions co;
  co.binning = o.binning;
  co.threads = o.threads;
  co.no_reflections = o.no_reflections;
  co.min_pixels = o.min_pixels;
  co.min_weight = o.min_weight;
  co.cache_dir = o.cache_dir;
  const fs::path parent = fs::path(o.output).parent_path();
  const CorrectionSettings s = settings(co, ((parent.empty() ? fs::path(".") : parent) / "glasspiv-cache").string());
  // Every output against every file the scene reads, before any work.
  const std::vector<std::string> inputs = scene_input_files(cs.scene);
  std::vector<OutputFile> outputs = {{o.output, "-o"}};
  for (int ci : indices) outputs.push_back({correction_cache_files(cs.scene, ci, s).map, "--cache-dir", OutputKind::transport_map});
  check_outputs(inputs, outputs);
  const SheetGrid grid =
      grid_for(cs, o.mm_per_px > 0 ? o.mm_per_px : glass_removed_view(cs, indices.front(), s).footprint_mm);
  for (int ci : indices) outputs.push_back({correction_cache_files(cs.scene, ci, s, grid.cols, grid.rows).op, "--cache-dir", OutputKind::correction_operator});
  check_outputs(inputs, outputs);
  std::printf("scene %s: sheet grid %dx%d cells of %.4g mm\n", o.scene.c_str(), grid.cols, grid.rows, grid.mm_per_px);
  for (int ci : indices) add_correction_camera(cs, ci, grid, s);
  const std::vector<CameraOperator> ops = camera_operators(cs);
  std::vector<int> count(grid.cell_count(), 0);
  for (std::size_t k = 0; k < ops.size(); ++k) {
    const std::vector<CellState> own = classify_cells({ops[k]}, cs.trace, s.mask);
    print_coverage(count_cells(own), ("camera '" + cs.cameras[k].name + "'").c_str());
    for (std::size_t c = 0; c < own.size(); ++c) count[c] += own[c] == CellState::valid;
  }
  const std::vector<CellState> together = classify_cells(ops, cs.trace, s.mask);
  const CellCounts n = count_cells(together);
  print_coverage(n, "together");
  std::printf("of what the cameras see without reflections, %.2f%% is reconstructable\n", 100 * n.valid_fraction_of_seen());
  // Colours (BGR): valid in greens, brighter with more cameras that see the cell alone; masked cells by reason.
  cv::Mat img(grid.rows, grid.cols, CV_8UC3);
  const int cams = static_cast<int>(ops.size());
  for (int r = 0; r < grid.rows; ++r)
    for (int c = 0; c < grid.cols; ++c) {
      const std::size_t i = static_cast<std::size_t>(r) * grid.cols + c;
      cv::Vec3b colour;
      switch (together[i]) {
        case CellState::valid: {
          const int g = 110 + 145 * std::max(count[i], 1) / std::max(cams, 1);
          colour = cv::Vec3b(60, static_cast<unsigned char>(g), 40);
          break;
        }
        case CellState::inside_solid: colour = cv::Vec3b(90, 60, 40); break;
        case CellState::never_seen: colour = cv::Vec3b(0, 0, 0); break;
        case CellState::few_pixels: colour = cv::Vec3b(40, 40, 200); break;
        case CellState::mostly_reflected: colour = cv::Vec3b(200, 60, 160); break;
        case CellState::low_weight: colour = cv::Vec3b(40, 160, 220); break;
      }
      img.at<cv::Vec3b>(r, c) = colour;
    }
  write_file_atomically_with(o.output, [&](const std::string& tmp) {
    if (!cv::imwrite(tmp, img)) throw InputError(o.output, "", "cannot write the PNG");
  });
  std::printf("wrote %s (%dx%d: green valid, brighter where more cameras see it alone; black never seen, red too few "
              "pixels, purple mostly reflected, orange too little weight, blue inside solids)\n",
              o.output.c_str(), grid.cols, grid.rows);
}

void add_common(CLI::App* c, CorrectOptions& o) {
  c->add_option("--mm-per-px", o.mm_per_px,
                "Sheet grid pitch in mm (default: the first camera's own pixel on the sheet, glass removed)")
      ->check(CLI::PositiveNumber);
  c->add_option("--method", o.method, "accumulate (back-projection, the published method) or lsq (least squares)")
      ->check(CLI::IsMember({"accumulate", "lsq"}))
      ->capture_default_str();
  c->add_option("--smoothness", o.smoothness, "Least squares: weight of the gradient penalty (dimensionless)")
      ->check(CLI::Range(0.0, 1e6))
      ->capture_default_str();
  c->add_option("--max-iterations", o.max_iterations, "Least squares: most CGLS iterations")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  c->add_option("--format", o.format, "Output pixels: 16 or float")->capture_default_str();
  c->add_option("--min-pixels", o.min_pixels,
                "Mask: fewest camera pixels per sheet cell (docs/correction.md)")
      ->check(CLI::Range(0.0, 1e6))
      ->capture_default_str();
  c->add_option("--min-weight", o.min_weight, "Mask: least light per pixel that sees a cell directly")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  c->add_option("--shard", o.shard, "K/N: correct frames K, K+N, K+2N, ... only (0 <= K < N; docs/cluster.md)");
  c->add_option("--cache-dir", o.cache_dir, "Where transport maps and operators are cached (default: beside the output)");
  c->add_flag("--no-cache", o.no_cache, "Trace and build without reading or writing a cache");
  c->add_flag("--prepare-only", o.prepare_only,
              "Build the caches and write the mask, correct no frame (before a job array: docs/cluster.md)");
  c->add_option("--binning", o.binning, "Cameras read out K x K binned (the frames must be too)")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  c->add_option("--samples", o.samples, "Map samples per pixel axis")->check(CLI::Range(1, 16))->capture_default_str();
  c->add_option("--trace-min-weight", o.trace_min_weight, "Map: branches below this weight are not followed")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  c->add_flag("--no-reflections", o.no_reflections, "Map: follow refracted branches only");
  c->add_option("--threads", o.threads, "Threads (default: all cores)")->check(CLI::NonNegativeNumber);
}

}  // namespace

void register_correct_commands(CLI::App& app) {
  auto o = std::make_shared<CorrectOptions>();
  CLI::App* c = app.add_subcommand(
      "correct",
      "Correct distorted PIV frames through the scene's model: one camera onto its own pixels with the glass removed "
      "(or onto the sheet grid), several cameras onto the sheet grid");
  c->add_option("scene", o->scene, "Scene file (docs/scene.md)")->required()->check(CLI::ExistingFile);
  c->add_option("images", o->images, "Frames of one camera: 8/16-bit or float TIFF (files or folders)");
  c->add_option("-o,--output", o->output,
                "Output folder (one corrected TIFF per frame, mask.tif); with --frame and one frame per camera, "
                "a .tif file")
      ->required();
  c->add_option("--camera", o->camera, "The camera of IMAGES (default: the scene's first)");
  c->add_option("--frame", o->frames,
                "CAMERA=FILE, CAMERA=FOLDER or CAMERA=PATTERN, once per camera: several cameras, frames matched by index");
  c->add_option("--camera-weight", o->camera_weights,
                "CAMERA=W: that camera's share in a multi-camera reconstruction (default 1; 0 leaves it out)");
  CLI::Option* grid = c->add_option("--grid", o->grid, "camera (the same camera with the glass removed; one camera only) or sheet (mm grid; the default with --frame)")
      ->check(CLI::IsMember({"camera", "sheet"}))
      ->capture_default_str();
  add_common(c, *o);
  c->callback([o, grid]() {
    CorrectOptions opts = *o;
    if (!opts.frames.empty() && grid->count() == 0) opts.grid = "sheet";
    run_correct(opts);
  });

  auto v = std::make_shared<CoverageOptions>();
  CLI::App* g = app.add_subcommand(
      "coverage", "Which parts of the sheet a set of cameras can reconstruct: a picture and the covered fractions");
  g->add_option("scene", v->scene, "Scene file (docs/scene.md)")->required()->check(CLI::ExistingFile);
  g->add_option("-o,--output", v->output, "Picture to write (.png)")->required();
  g->add_option("--camera", v->cameras, "Cameras to use (repeat; default: all of the scene's)");
  g->add_option("--mm-per-px", v->mm_per_px, "Sheet grid pitch in mm (default: the first camera's pixel on the sheet)")
      ->check(CLI::PositiveNumber);
  g->add_option("--min-pixels", v->min_pixels, "Mask: fewest camera pixels per sheet cell")
      ->check(CLI::Range(0.0, 1e6))
      ->capture_default_str();
  g->add_option("--min-weight", v->min_weight, "Mask: least light per pixel that sees a cell directly")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  g->add_option("--binning", v->binning, "Cameras read out K x K binned (a quick plan)")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  g->add_option("--cache-dir", v->cache_dir, "Where maps and operators are cached (default: beside the picture)");
  g->add_flag("--no-reflections", v->no_reflections, "Follow refracted branches only");
  g->add_option("--threads", v->threads, "Threads (default: all cores)")->check(CLI::NonNegativeNumber);
  g->callback([v]() { run_coverage(*v); });
}

}  // namespace glasspiv
