#pragma once
// Mesh solids from CAD files: STL (ASCII or binary), OBJ and PLY, read with
// assimp and turned into a TriangleMesh (render/triangle_mesh.h) in the world
// frame. The scene syntax is in docs/scene.md ("Meshes").
//
// - The file's numbers are in "file units"; placement.scale converts them to mm
//   (1000 for a file in metres). p_world = world_from_mesh (scale p_file) + position_mm.
// - assimp only triangulates (polygons -> triangles) and validates; it moves no
//   vertex. Corners at exactly the same position are then welded into one
//   vertex (STL stores every triangle on its own), so a watertight file gives a
//   closed mesh; the mesh must be closed (open meshes are refused).
// - Points and lines in the file are ignored; every triangle of every mesh in
//   the file (with the file's node transforms) belongs to the one solid.
// - assimp prints nothing (no logger is attached).
#include <Eigen/Core>
#include <optional>
#include <string>

#include "render/triangle_mesh.h"

namespace glasspiv {

struct Scene;
struct MeshSolid;

enum class MeshNormals {
  flat,    // the triangles' own normals
  smooth,  // angle-weighted vertex normals computed from the mesh (sharp edges beyond the crease angle kept)
  file,    // the file's normals (OBJ vn, PLY nx ny nz, STL facet normals); computed smooth ones if it has none
};
const char* mesh_normals_name(MeshNormals normals);
// "flat", "smooth", "file"; std::nullopt otherwise.
std::optional<MeshNormals> mesh_normals_from_name(const std::string& name);

struct MeshPlacement {
  double scale = 1;  // file units -> mm (> 0)
  Eigen::Matrix3d world_from_mesh = Eigen::Matrix3d::Identity();  // a rotation
  Eigen::Vector3d position_mm = Eigen::Vector3d::Zero();
};

struct MeshLoadOptions {
  MeshNormals normals = MeshNormals::smooth;
  double crease_angle_deg = 60;  // for computed smooth normals, see MeshBuildOptions
};

// The triangles of a file, placed and welded, before any check. With
// with_normals, the file's normals (placed: rotated) per corner, when it has
// them for every triangle. Throws InputError(path, "", reason) for a missing
// file, an extension other than .stl/.obj/.ply, a file assimp cannot parse, or
// a file without triangles.
MeshArrays read_mesh_arrays(const std::string& path, const MeshPlacement& placement = {}, bool with_normals = false);

// read_mesh_arrays + build_triangle_mesh; a mesh the builder refuses (open,
// inconsistent, degenerate triangles, ...) is InputError(path, "", reason).
TriangleMesh load_mesh(const std::string& path, const MeshPlacement& placement = {}, const MeshLoadOptions& opts = {});

// The mesh of a scene's MeshSolid; a missing or bad file is
// InputError(scene.source, mesh.field + ".file", "mesh file '<path>': reason").
TriangleMesh load_scene_mesh(const Scene& scene, const MeshSolid& mesh);

}  // namespace glasspiv
