#include "apps/demo_correction.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "apps/correction_setup.h"
#include "apps/png_file.h"
#include "correct/reconstruct.h"
#include "render/forward_render.h"
#include "render/sheet_pattern.h"
#include "sim/sheet_particles.h"
#include "util/atomic_file.h"
#include "util/image_file.h"
#include "util/input_error.h"
#include "util/stopwatch.h"

namespace glasspiv {
namespace {
namespace fs = std::filesystem;

// PIV-like particles: 3 px images, 0.03 per px of the undistorted view.
SheetPicture particles(const SheetPlane& sheet, double px_mm, double mm_per_texel) {
  return particle_picture(sheet.extent_s_mm, sheet.extent_t_mm, 0.03 / (px_mm * px_mm), 3 * px_mm, mm_per_texel, 11);
}

cv::Mat to8(const std::vector<float>& v, int w, int h, double gain) {
  cv::Mat m(h, w, CV_32F, const_cast<float*>(v.data()));
  cv::Mat out;
  m.convertTo(out, CV_8U, 255 * gain);
  return out;
}

// Images side by side with a grey gutter.
cv::Mat side_by_side(const std::vector<cv::Mat>& images) {
  std::vector<cv::Mat> parts;
  for (std::size_t i = 0; i < images.size(); ++i) {
    if (i) parts.push_back(cv::Mat(images[i].rows, 8, CV_8U, cv::Scalar(128)));
    parts.push_back(images[i]);
  }
  cv::Mat out;
  cv::hconcat(parts, out);
  return out;
}

}  // namespace

DemoCorrectionSummary run_correction_demo(const std::string& folder, const std::string& scenes_dir, int binning) {
  const fs::path out(folder);
  fs::create_directories(out);
  DemoCorrectionSummary s;
  CorrectionSettings settings;
  settings.binning = binning;
  settings.cache_dir = (out / "cache").string();
  settings.report = false;

  // One camera, onto its own pixels with the glass removed.
  std::printf("   one camera: its correction operator (from the cache if valid)...\n");
  {
    CorrectionScene cs = read_correction_scene((fs::path(scenes_dir) / "reactor.yaml").string());
    const GlassRemovedView direct = glass_removed_view(cs, 0, settings);
    const SheetGrid grid = sheet_grid_covering(cs.trace.sheet, direct.footprint_mm);
    const Stopwatch clock;
    add_correction_camera(cs, 0, grid, settings);
    s.operator_seconds = clock.seconds();
    const CorrectionCamera& cam = cs.cameras.front();
    s.width = cam.model.width_px();
    s.height = cam.model.height_px();
    const std::vector<CellState> states = classify_cells(camera_operators(cs), cs.trace, settings.mask);
    s.one_valid_fraction = count_cells(states).valid_fraction_of_fluid();

    std::printf("   one camera: rendering a distorted frame and correcting it...\n");
    // The distorted frame: the field at 4x finer texels, footprint-filtered through the map's operator.
    const SheetPicture fine = particles(cs.trace.sheet, direct.footprint_mm, direct.footprint_mm / 4);
    const SheetPicture truth = particles(cs.trace.sheet, direct.footprint_mm, direct.footprint_mm);
    TransportMap map = build_transport_map(cs.trace, cam.model, cam.pose, settings.trace, 1);
    const std::vector<float> frame =
        forward_render_values(map, SheetTexture(fine.values.data(), fine.rows, fine.cols, fine.mm_per_texel));
    map = TransportMap{};
    // What the camera records without the glass: the truth for the camera grid.
    const std::vector<float> reference =
        forward_render_values(direct.map, SheetTexture(fine.values.data(), fine.rows, fine.cols, fine.mm_per_texel));

    const CameraResampler resampler =
        make_camera_resampler(build_correction_operator(direct.map, grid, settings.op), states);
    std::vector<float> corrected(frame.size()), corrected_lsq(frame.size());
    const std::vector<CameraImage> views = {{&cam.op, frame.data()}};
    const Stopwatch per_frame;
    const std::vector<float> l = back_projection(views, states);
    resample_to_camera(resampler, l.data(), corrected.data());
    s.correct_ms = 1e3 * per_frame.seconds();
    const std::vector<float> l_lsq = least_squares(views, states, l);
    resample_to_camera(resampler, l_lsq.data(), corrected_lsq.data());
    s.one_ncc = ncc_where(corrected, reference, resampler.pixel_valid);
    s.one_lsq_ncc = ncc_where(corrected_lsq, reference, resampler.pixel_valid);
    if (truth.cols != grid.cols || truth.rows != grid.rows) throw std::logic_error("demo: truth not on the grid");

    s.corrected_tif = (out / "reactor_corrected.tif").string();
    s.mask_tif = (out / "reactor_corrected_mask.tif").string();
    write_gray_image((out / "reactor_distorted.tif").string(), frame.data(), s.width, s.height, PixelFormat::uint16);
    write_gray_image(s.corrected_tif, corrected_lsq.data(), s.width, s.height, PixelFormat::uint16);
    std::vector<float> mask(resampler.pixel_valid.begin(), resampler.pixel_valid.end());
    for (float& v : mask) v /= 255;
    write_gray_image(s.mask_tif, mask.data(), s.width, s.height, PixelFormat::uint8);
    s.side_by_side_png = (out / "reactor_distorted_corrected_reference.png").string();
    write_png(s.side_by_side_png, side_by_side({to8(frame, s.width, s.height, 1), to8(corrected_lsq, s.width, s.height, 1),
                                                to8(reference, s.width, s.height, 1), to8(mask, s.width, s.height, 1)}));
  }

  // Five cameras, onto the sheet grid.
  std::printf("   five cameras: their correction operators (from the cache if valid)...\n");
  {
    CorrectionSettings five = settings;
    five.binning = 2 * binning;
    CorrectionScene cs = read_correction_scene((fs::path(scenes_dir) / "reactor_5cams.yaml").string());
    const int centre = find_camera(cs.scene, "cam_centre", "cameras");
    const GlassRemovedView direct = glass_removed_view(cs, centre, five);
    const SheetGrid grid = sheet_grid_covering(cs.trace.sheet, direct.footprint_mm);
    for (int k = 0; k < static_cast<int>(cs.scene.cameras.size()); ++k) add_correction_camera(cs, k, grid, five);
    const std::vector<CameraOperator> ops = camera_operators(cs);
    const std::vector<CellState> together = classify_cells(ops, cs.trace, five.mask);
    const CellCounts n = count_cells(together);
    s.five_valid_fraction = n.valid_fraction_of_fluid();
    s.five_seen_fraction = n.valid_fraction_of_seen();
    s.centre_valid_fraction =
        count_cells(classify_cells({ops[static_cast<std::size_t>(centre)]}, cs.trace, five.mask)).valid_fraction_of_fluid();

    std::printf("   five cameras: rendering their frames, then accumulation and least squares...\n");
    const SheetPicture fine = particles(cs.trace.sheet, direct.footprint_mm, direct.footprint_mm / 4);
    const SheetPicture truth = particles(cs.trace.sheet, direct.footprint_mm, direct.footprint_mm);
    const SheetTexture texture(fine.values.data(), fine.rows, fine.cols, fine.mm_per_texel);
    std::vector<std::vector<float>> frames;
    std::vector<CameraImage> views;
    for (const CorrectionCamera& cam : cs.cameras)
      frames.push_back(forward_render_values(build_transport_map(cs.trace, cam.model, cam.pose, five.trace, 1), texture));
    for (std::size_t k = 0; k < cs.cameras.size(); ++k) views.push_back({&cs.cameras[k].op, frames[k].data()});
    const std::vector<float> acc = back_projection(views, together);
    LeastSquaresReport rep;
    const std::vector<float> lsq = least_squares(views, together, acc, {}, &rep);
    s.lsq_iterations = rep.iterations;
    s.accumulation_rms = rms_difference_where(acc, truth.values, valid_cells(together));
    s.lsq_rms = rms_difference_where(lsq, truth.values, valid_cells(together));
    std::vector<float> valid(together.size());
    for (std::size_t i = 0; i < valid.size(); ++i) valid[i] = together[i] == CellState::valid;
    s.five_png = (out / "reactor_5cams_truth_accumulation_lsq.png").string();
    write_png(s.five_png, side_by_side({to8(truth.values, grid.cols, grid.rows, 1), to8(acc, grid.cols, grid.rows, 1),
                                        to8(lsq, grid.cols, grid.rows, 1), to8(valid, grid.cols, grid.rows, 1)}));
  }
  return s;
}

}  // namespace glasspiv
