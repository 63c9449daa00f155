// Writes the seeds of the fuzz corpora that data/ has no file for (docs/fuzzing.md):
//   <out>/transport_map/      two small maps (with and without the footprint Jacobian)
//   <out>/correction_operator/ a small operator
//   <out>/observations_yaml/, observations_json/  a two-view observations file
//   <out>/camera_<format>/    the cameras of data/cameras/ in every format that holds them
//   <out>/image/              tiny PNG (8, 16 bit), TIFF (8, 16, float), EXR, JPEG (gray, RGB)
// Usage: fuzz_make_seeds <out folder> <data/cameras folder>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "calib/io/camera_file.h"
#include "calib/observations.h"
#include "correct/correction_operator.h"
#include "correct/correction_operator_file.h"
#include "render/transport_map_file.h"
#include "targets/observations_io.h"
#include "util/image_file.h"
#include "util/input_error.h"

namespace fs = std::filesystem;
using namespace glasspiv;

namespace {

void write_text(const fs::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

TransportMap small_map(bool footprint) {
  TransportMap map;
  map.width = 3;
  map.height = 2;
  map.samples_per_axis = 1;
  const int counts[6] = {1, 0, 2, 1, 3, 1};
  map.pixel_offsets = {0};
  for (int p = 0; p < 6; ++p) {
    for (int k = 0; k < counts[p]; ++k) {
      map.s_mm.push_back(0.5f * static_cast<float>(p) - 1.0f);
      map.t_mm.push_back(0.25f * static_cast<float>(k) + 0.125f);
      map.weight.push_back(0.9f / static_cast<float>(counts[p]));
      map.tag.push_back(static_cast<std::uint8_t>(k % 3));
      if (footprint) {
        map.ds_dcol.push_back(0.05f);
        map.ds_drow.push_back(-0.001f);
        map.dt_dcol.push_back(0.002f);
        map.dt_drow.push_back(-0.05f);
      }
    }
    map.pixel_offsets.push_back(static_cast<std::uint32_t>(map.weight.size()));
    map.background_weight.push_back(p == 1 ? 1.0f : 0.1f);
    map.opaque_weight.push_back(p == 1 ? 0.0f : 0.05f);
  }
  map.stats.camera_rays = 6;
  map.stats.branches_traced = 14;
  map.stats.crossings = static_cast<long>(map.weight.size());
  map.stats.cut_weight = 0.01;
  map.stats.threads = 1;
  return map;
}

CorrectionOperator small_operator() {
  CorrectionOperator op;
  op.width = 3;
  op.height = 2;
  op.grid.cols = 4;
  op.grid.rows = 3;
  op.grid.mm_per_px = 0.5;
  op.grid.s0_mm = -1;
  op.grid.t0_mm = 1;
  const int counts[6] = {2, 0, 3, 1, 1, 2};
  op.pixel_offsets = {0};
  for (int p = 0; p < 6; ++p) {
    for (int k = 0; k < counts[p]; ++k) {
      op.cell.push_back(static_cast<std::uint32_t>((p * 5 + k * 3) % 11));
      op.value.push_back(0.1f * static_cast<float>(p + 1) + 0.01f * static_cast<float>(k));
    }
    op.pixel_offsets.push_back(static_cast<std::uint32_t>(op.cell.size()));
    op.background_weight.push_back(0.125f * static_cast<float>(p));
  }
  for (int c = 0; c < 12; ++c) {
    op.cell_pixels.push_back(c == 11 ? 0.0f : 0.25f * static_cast<float>(c + 1));
    op.cell_direct_pixels.push_back(c % 2 == 0 ? 0.0f : 0.125f * static_cast<float>(c + 1));
  }
  finish_correction_operator(op);
  return op;
}

Observations small_observations() {
  Observations obs;
  obs.image_width_px = 640;
  obs.image_height_px = 480;
  obs.target_name = "chessboard_9x6";
  for (int v = 0; v < 2; ++v) {
    ViewObservations view;
    view.source = "shots/000" + std::to_string(v + 1) + ".png";
    for (int id = 0; id < 4; ++id) {
      CornerObservation c;
      c.id = id + v;
      c.pixel_px = {100.25 + 30 * id + v, 200.5 + 2 * id};
      c.board_point_mm = {25.0 * (id % 2), 25.0 * (id / 2), 0};
      view.corners.push_back(c);
    }
    obs.views.push_back(view);
  }
  obs.views.push_back(ViewObservations{"shots/empty.png", {}});
  return obs;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: %s <out folder> <data/cameras folder>\n", argv[0]);
    return 2;
  }
  const fs::path out = argv[1];
  for (const char* sub : {"transport_map", "correction_operator", "observations_yaml", "observations_json", "image"})
    fs::create_directories(out / sub);

  write_transport_map((out / "transport_map" / "small_footprint.tmap").string(), small_map(true), 0x0123456789abcdefULL);
  write_transport_map((out / "transport_map" / "small_plain.tmap").string(), small_map(false), 42);
  write_correction_operator((out / "correction_operator" / "small.gpop").string(), small_operator(), 7);

  const Observations obs = small_observations();
  write_text(out / "observations_yaml" / "two_views.yaml", format_observations(obs, ObservationsFormat::yaml));
  write_text(out / "observations_json" / "two_views.json", format_observations(obs, ObservationsFormat::json));

  std::vector<float> gray(6 * 4);
  for (std::size_t i = 0; i < gray.size(); ++i) gray[i] = static_cast<float>(i) / static_cast<float>(gray.size());
  const fs::path img = out / "image";
  write_gray_image((img / "gray8.png").string(), gray.data(), 6, 4, PixelFormat::uint8);
  write_gray_image((img / "gray16.png").string(), gray.data(), 6, 4, PixelFormat::uint16);
  write_gray_image((img / "gray8.tif").string(), gray.data(), 6, 4, PixelFormat::uint8);
  write_gray_image((img / "gray16.tif").string(), gray.data(), 6, 4, PixelFormat::uint16);
  write_gray_image((img / "float.tif").string(), gray.data(), 6, 4, PixelFormat::float32);
  write_gray_image((img / "float.exr").string(), gray.data(), 6, 4, PixelFormat::float32);
  cv::Mat g8(4, 6, CV_8UC1), rgb(4, 6, CV_8UC3);
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 6; ++c) {
      g8.at<unsigned char>(r, c) = static_cast<unsigned char>(10 * (r * 6 + c));
      rgb.at<cv::Vec3b>(r, c) = cv::Vec3b(static_cast<unsigned char>(40 * r), static_cast<unsigned char>(40 * c), 200);
    }
  cv::imwrite((img / "gray.jpg").string(), g8);
  cv::imwrite((img / "rgb.jpg").string(), rgb);
  cv::imwrite((img / "rgb.png").string(), rgb);
  // Cameras: each file of data/cameras in every format, and all of them in one file.
  std::vector<Camera> all;
  for (const auto& e : fs::directory_iterator(argv[2])) {
    const std::string ext = e.path().extension().string();
    if (ext != ".yaml" && ext != ".cameramodel" && ext != ".xml") continue;
    for (const Camera& cam : read_cameras(e.path().string())) all.push_back(cam);
  }
  const std::pair<CameraFileFormat, const char*> formats[] = {{CameraFileFormat::Glasspiv, ".yaml"},
                                                              {CameraFileFormat::OpenCV, ".yaml"},
                                                              {CameraFileFormat::Mrcal, ".cameramodel"},
                                                              {CameraFileFormat::Davis, ".xml"}};
  for (const auto& [format, ext] : formats) {
    const fs::path dir = out / ("camera_" + format_name(format));
    fs::create_directories(dir);
    for (std::size_t i = 0; i < all.size(); ++i) {
      try {
        const std::string name = all[i].name.empty() ? "camera" + std::to_string(i) : all[i].name;
        write_text(dir / ("from_" + name + ext), format_cameras({all[i]}, format, "seed" + std::string(ext)));
      } catch (const InputError& e) {
        std::printf("skipped: %s\n", e.what());
      }
    }
    try {
      write_text(dir / (std::string("all") + ext), format_cameras(all, format, "seed" + std::string(ext)));
    } catch (const InputError& e) {
      std::printf("skipped: %s\n", e.what());
    }
  }
  std::printf("seeds written under %s\n", out.string().c_str());
  return 0;
}
