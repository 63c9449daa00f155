// glasspiv piv: one frame pair -> a vector file (piv/piv_evaluate.h; docs/piv.md).
#include <cstdio>
#include <memory>
#include <optional>

#include <fmt/format.h>

#include "apps/cli_checks.h"
#include "apps/cli_files.h"
#include "apps/commands.h"
#include "piv/piv_evaluate.h"
#include "piv/vector_file.h"
#include "util/image_file.h"
#include "util/input_error.h"
#include "util/progress_bar.h"
#include "util/stopwatch.h"

namespace glasspiv {
namespace {

// The most vectors one run may make (a text file of ~50 bytes each: 2.5 GB).
constexpr double kMaxPivVectors = 5e7;

struct PivCommandOptions {
  std::string frame_a, frame_b, mask, output, vtk, interpolation = "bspline5";
  std::vector<int> window_px{64, 32};
  double overlap = 0.5;
  int threads = 0;
};

cv::Mat as_mat(GrayImage& image) { return cv::Mat(image.height, image.width, CV_32F, image.values.data()); }

std::string size_text(const GrayImage& g) { return fmt::format("{}x{} px", g.width, g.height); }

PivOptions library_options(const PivCommandOptions& o) {
  PivOptions p;
  p.window_px = o.window_px;
  p.overlap = o.overlap;
  p.threads = o.threads;
  for (DeformInterpolation k : {DeformInterpolation::bilinear, DeformInterpolation::bicubic,
                                DeformInterpolation::bspline3, DeformInterpolation::bspline5})
    if (o.interpolation == deform_interpolation_name(k)) p.interpolation = k;
  for (int n : o.window_px)
    if (n < 8 || n > 4096)
      throw InputError("", "--window", fmt::format("{} px: each window must be 8 to 4096 px", n));
  if (o.window_px.empty()) throw InputError("", "--window", "give at least one window size (e.g. 64,32)");
  if (!(o.overlap >= 0 && o.overlap <= 0.9))
    throw InputError("", "--overlap", fmt::format("{} must lie in [0, 0.9]", number(o.overlap)));
  return p;
}

void run_piv(const PivCommandOptions& o) {
  const PivOptions options = library_options(o);
  std::vector<std::string> inputs{o.frame_a, o.frame_b};
  if (!o.mask.empty()) inputs.push_back(o.mask);
  std::vector<OutputFile> outputs{{o.output, "-o", OutputKind::text}};
  if (!o.vtk.empty()) {
    if (lower_extension(o.vtk) != ".vtk") throw InputError(o.vtk, "--vtk", "must end in .vtk");
    outputs.push_back({o.vtk, "--vtk", OutputKind::text});
  }
  check_outputs(inputs, outputs);

  GrayImage a = read_gray_image(o.frame_a), b = read_gray_image(o.frame_b);
  if (a.width != b.width || a.height != b.height)
    throw InputError(o.frame_b, "image size",
                     fmt::format("{}, but frame A ({}) is {}", size_text(b), o.frame_a, size_text(a)));
  cv::Mat usable;
  if (!o.mask.empty()) {
    GrayImage m = read_gray_image(o.mask);
    if (m.width != a.width || m.height != a.height)
      throw InputError(o.mask, "image size", fmt::format("{}, but the frames are {}", size_text(m), size_text(a)));
    usable = as_mat(m) > 0;  // 255 / 0
    usable /= 255;
  }
  for (int n : options.window_px)
    if (n > a.width || n > a.height)
      throw InputError("", "--window",
                       fmt::format("a {} px window does not fit in the {} frames", n, size_text(a)));
  const InterrogationGrid grid = final_piv_grid(a.width, a.height, options);
  if (grid.size() > kMaxPivVectors)
    throw InputError("", "--overlap",
                     fmt::format("{} x {} vectors exceed the limit of {}; use a smaller overlap or larger windows",
                                 grid.cols, grid.rows, number(kMaxPivVectors)));

  // The bar appears only once the run has taken a second.
  const Stopwatch clock;
  std::unique_ptr<ProgressBar> bar;
  const PivField field = evaluate_piv(as_mat(a), as_mat(b), usable, options, [&](std::size_t done, std::size_t total) {
    if (!bar && clock.seconds() > 1 && done < total) bar = std::make_unique<ProgressBar>("piv", total, "windows");
    if (bar) bar->set_done(done);
  });
  if (bar) bar->finish();
  const double seconds = clock.seconds();

  std::size_t valid = 0, replaced = 0, invalid = 0;
  for (VectorFlag f : field.flags) {
    valid += f == VectorFlag::valid;
    replaced += f == VectorFlag::replaced;
    invalid += f == VectorFlag::invalid;
  }
  std::string windows;
  for (int n : options.window_px) windows += (windows.empty() ? "" : ",") + std::to_string(n);
  const std::vector<std::string> comments{
      "frame A: " + o.frame_a, "frame B: " + o.frame_b, "mask: " + (o.mask.empty() ? std::string("none") : o.mask),
      fmt::format("passes: windows {} px, overlap {}, deformation {}", windows, number(options.overlap),
                  deform_interpolation_name(options.interpolation)),
      fmt::format("vectors: {} valid, {} replaced, {} invalid", valid, replaced, invalid)};
  write_vector_files(o.output, o.vtk, field, comments);
  std::printf("%d x %d vectors (window %d px, step %d px) in %.2f s: %zu valid, %zu replaced, %zu invalid\n",
              grid.cols, grid.rows, grid.window_px, grid.step_px, seconds, valid, replaced, invalid);
  std::printf("wrote %s%s%s\n", o.output.c_str(), o.vtk.empty() ? "" : " and ", o.vtk.c_str());
}

}  // namespace

void register_piv_command(CLI::App& app) {
  auto o = std::make_shared<PivCommandOptions>();
  CLI::App* c = app.add_subcommand(
      "piv", "PIV of one frame pair: multi-pass cross-correlation with window deformation -> a vector file "
             "(u, v: displacement of B relative to A in px, u along +x (columns), v along +y (rows); docs/piv.md)");
  c->add_option("frame_a", o->frame_a, "First frame (8/16-bit or float image)")->required()->check(CLI::ExistingFile);
  c->add_option("frame_b", o->frame_b, "Second frame, the same size")->required()->check(CLI::ExistingFile);
  c->add_option("-o,--output", o->output, "Vector file to write (text: x_px y_px u_px v_px flag peak_ratio)")
      ->required();
  c->add_option("--mask", o->mask,
                "Image of the frames' size: nonzero = usable, 0 = masked (glasspiv correct's mask.tif reads so)")
      ->check(CLI::ExistingFile);
  c->add_option("--window", o->window_px, "Window side per pass in px, comma-separated (e.g. 64,32 or 64,32,32)")
      ->delimiter(',')
      ->capture_default_str();
  c->add_option("--overlap", o->overlap, "Fraction of a window shared with the next, 0 to 0.9")->capture_default_str();
  c->add_option("--interpolation", o->interpolation, "Window deformation: bilinear, bicubic, bspline3 or bspline5")
      ->check(CLI::IsMember({"bilinear", "bicubic", "bspline3", "bspline5"}))
      ->capture_default_str();
  c->add_option("--vtk", o->vtk, "Also write the field as VTK legacy structured points (.vtk)");
  c->add_option("--threads", o->threads, "Threads (default: all cores)")->check(CLI::NonNegativeNumber);
  c->callback([o]() { run_piv(*o); });
}

}  // namespace glasspiv
