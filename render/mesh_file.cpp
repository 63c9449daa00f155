#include "render/mesh_file.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <unordered_map>

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <fmt/format.h>

#include "render/scene.h"
#include "util/input_error.h"
#include "util/input_file.h"

namespace glasspiv {

const char* mesh_normals_name(MeshNormals normals) {
  switch (normals) {
    case MeshNormals::flat: return "flat";
    case MeshNormals::smooth: return "smooth";
    case MeshNormals::file: return "file";
  }
  return "?";
}

std::optional<MeshNormals> mesh_normals_from_name(const std::string& name) {
  if (name == "flat") return MeshNormals::flat;
  if (name == "smooth") return MeshNormals::smooth;
  if (name == "file") return MeshNormals::file;
  return std::nullopt;
}

namespace {

namespace fs = std::filesystem;
using Eigen::Matrix3d;
using Eigen::Vector3d;

// Exact positions as keys (-0 and +0 are the same position).
struct PositionHash {
  std::size_t operator()(const std::array<double, 3>& p) const {
    std::size_t h = 1469598103934665603ull;
    for (double x : p) {
      std::uint64_t bits;
      std::memcpy(&bits, &x, sizeof bits);
      h = (h ^ bits) * 1099511628211ull;
      h ^= h >> 29;
    }
    return h;
  }
};

struct Affine {
  Matrix3d linear = Matrix3d::Identity();
  Vector3d translation = Vector3d::Zero();
};

Affine node_affine(const aiMatrix4x4& t) {
  Affine a;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) a.linear(r, c) = t[r][c];
    a.translation[r] = t[r][3];
  }
  return a;
}

class Collector {
 public:
  Collector(const aiScene& scene, const MeshPlacement& placement, bool with_normals)
      : scene_(scene), placement_(placement), with_normals_(with_normals) {
    for (unsigned i = 0; i < scene.mNumMeshes; ++i)
      if (!scene.mMeshes[i]->HasNormals()) with_normals_ = false;
  }

  void node(const aiNode* n, const Affine& parent) {
    Affine world;
    const Affine local = node_affine(n->mTransformation);
    world.linear = parent.linear * local.linear;
    world.translation = parent.linear * local.translation + parent.translation;
    for (unsigned i = 0; i < n->mNumMeshes; ++i)
      if (n->mMeshes[i] < scene_.mNumMeshes) mesh(*scene_.mMeshes[n->mMeshes[i]], world);
    for (unsigned i = 0; i < n->mNumChildren; ++i) node(n->mChildren[i], world);
  }

  void mesh(const aiMesh& mesh, const Affine& node) {
    const Matrix3d normal_matrix = placement_.world_from_mesh * node.linear.inverse().transpose();
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
      const aiFace& face = mesh.mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines bound nothing
      MeshTriangle t{};
      std::array<Vector3d, 3> p;
      for (int c = 0; c < 3; ++c) {
        const aiVector3D& v = mesh.mVertices[face.mIndices[c]];
        const Vector3d in_file = node.linear * Vector3d(v.x, v.y, v.z) + node.translation;
        p[c] = placement_.world_from_mesh * (placement_.scale * in_file) + placement_.position_mm;
        t[c] = weld(p[c]);
      }
      arrays_.triangles.push_back(t);
      if (with_normals_) {
        const Vector3d geometric = (p[1] - p[0]).cross(p[2] - p[0]);
        for (int c = 0; c < 3; ++c) {
          const aiVector3D& n = mesh.mNormals[face.mIndices[c]];
          Vector3d placed = normal_matrix * Vector3d(n.x, n.y, n.z);
          // A file may store zero normals ("facet normal 0 0 0"): use the triangle's own.
          if (!placed.allFinite() || placed.norm() == 0) placed = geometric.norm() > 0 ? geometric : Vector3d::UnitZ();
          const auto k = static_cast<std::uint32_t>(arrays_.normals.size());
          arrays_.normals.push_back(placed);
          corner_normals_.push_back(k);
        }
      }
    }
  }

  MeshArrays take() {
    if (with_normals_) {
      arrays_.normal_triangles.resize(arrays_.triangles.size());
      for (std::size_t k = 0; k < arrays_.triangles.size(); ++k)
        for (int c = 0; c < 3; ++c) arrays_.normal_triangles[k][c] = corner_normals_[3 * k + c];
    }
    return std::move(arrays_);
  }

 private:
  std::uint32_t weld(const Vector3d& p) {
    const std::array<double, 3> key{p.x() + 0.0, p.y() + 0.0, p.z() + 0.0};
    const auto [it, inserted] = index_.try_emplace(key, static_cast<std::uint32_t>(arrays_.vertices_mm.size()));
    if (inserted) arrays_.vertices_mm.push_back(p);
    return it->second;
  }

  const aiScene& scene_;
  const MeshPlacement& placement_;
  bool with_normals_;
  MeshArrays arrays_;
  std::vector<std::uint32_t> corner_normals_;
  std::unordered_map<std::array<double, 3>, std::uint32_t, PositionHash> index_;
};

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

}  // namespace

MeshArrays read_mesh_arrays(const std::string& path, const MeshPlacement& placement, bool with_normals) {
  auto fail = [&](const std::string& reason) { throw InputError(path, "", reason); };
  check_input_file(path);  // a regular file (a fifo would block the importer)
  const std::string ext = lower(fs::path(path).extension().string());
  if (ext != ".stl" && ext != ".obj" && ext != ".ply")
    fail("unsupported mesh file type '" + ext + "' (STL, OBJ or PLY: .stl, .obj, .ply)");
  if (!(placement.scale > 0) || !std::isfinite(placement.scale))
    fail(fmt::format("the scale must be positive, got {}", placement.scale));
  if (!placement.world_from_mesh.allFinite() || !placement.position_mm.allFinite())
    fail("the placement must be finite");

  // Triangulate only: no step that merges, moves or drops vertices (JoinIdenticalVertices
  // would also compare normals, so it cannot weld STL; welding is done below, exactly).
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(path, aiProcess_Triangulate | aiProcess_ValidateDataStructure);
  if (!scene) {
    std::string why = importer.GetErrorString();
    std::replace(why.begin(), why.end(), '\n', ' ');
    fail("cannot be read as " + ext.substr(1) + (why.empty() ? "" : ": " + why));
  }
  Collector collect(*scene, placement, with_normals);
  if (scene->mRootNode) {
    collect.node(scene->mRootNode, Affine{});
  } else {
    for (unsigned i = 0; i < scene->mNumMeshes; ++i) collect.mesh(*scene->mMeshes[i], Affine{});
  }
  MeshArrays arrays = collect.take();
  if (arrays.triangles.empty()) fail("the file contains no triangle mesh");
  return arrays;
}

TriangleMesh load_mesh(const std::string& path, const MeshPlacement& placement, const MeshLoadOptions& opts) {
  MeshArrays arrays = read_mesh_arrays(path, placement, opts.normals == MeshNormals::file);
  MeshBuildOptions build;
  build.shading = opts.normals == MeshNormals::flat ? MeshShading::flat : MeshShading::smooth;
  build.crease_angle_deg = opts.crease_angle_deg;
  try {
    return build_triangle_mesh(std::move(arrays), build);
  } catch (const std::invalid_argument& e) {
    throw InputError(path, "", e.what());
  }
}

TriangleMesh load_scene_mesh(const Scene& scene, const MeshSolid& mesh) {
  try {
    return load_mesh(mesh.file, mesh.placement, mesh.options);
  } catch (const InputError& e) {
    throw InputError(scene.source, mesh.field + ".file", "mesh file '" + mesh.file + "': " + e.problem());
  }
}

}  // namespace glasspiv
