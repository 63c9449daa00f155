#pragma once
// The scene description: what the tracer is built from. Pure data plus
// validation, no I/O (render/scene_yaml.h reads it from a file; docs/scene.md is
// the file format). Units: mm, nm; rotations are stored as matrices (files give
// degrees or radians as docs/scene.md says). World frame: the user's; every pose
// is destination_from_source (docs/conventions.md).
#include <cstddef>
#include <array>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "calib/camera.h"
#include "render/material.h"
#include "render/mesh_file.h"

namespace glasspiv {

// Every element remembers where it came from ("solids[3]", "packings[0].spheres[1,0,2]")
// so that validation errors can name the field.
struct SphereSolid {
  Eigen::Vector3d centre_mm = Eigen::Vector3d::Zero();
  double diameter_mm = 0;
  std::string material;
  std::string field;
};

// A box: size_mm along its own x, y, z axes; world_from_box maps box axes to world.
struct BoxSolid {
  Eigen::Vector3d centre_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d size_mm = Eigen::Vector3d::Zero();
  Eigen::Matrix3d world_from_box = Eigen::Matrix3d::Identity();
  std::string material;
  std::string field;
};

// A slab (window, wall): one face is the plane through point_mm with the given
// normal; the slab extends thickness_mm from it along +normal. extent_mm is its
// size in the plane, [along u, along up], u = up x normal; the face's centre is point_mm.
struct SlabSolid {
  Eigen::Vector3d point_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  double thickness_mm = 0;
  std::array<double, 2> extent_mm{0, 0};
  Eigen::Vector3d up = Eigen::Vector3d::UnitY();  // in-plane direction of extent_mm[1]
  std::string material;
  std::string field;

  // The same solid as a box (box z = normal, box y = up made orthogonal to the normal).
  BoxSolid to_box() const;
};

// A solid circular cylinder from base_centre_mm along the unit axis for length_mm.
struct CylinderSolid {
  Eigen::Vector3d base_centre_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  double radius_mm = 0;
  double length_mm = 0;
  std::string material;
  std::string field;
};

// A thin rectangle (target, marker sheet, textured backdrop), seen from both sides.
// size_mm = [width along right = up x normal, height along up].
struct RectangleSolid {
  Eigen::Vector3d centre_mm = Eigen::Vector3d::Zero();
  std::array<double, 2> size_mm{0, 0};
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d up = Eigen::Vector3d::UnitY();
  std::string texture;   // image path as resolved by the reader ("" = none)
  std::string material;  // "" = opaque white (albedo 1) under the texture
  std::string field;
};

// A triangle-mesh solid from a CAD file (STL, OBJ, PLY). The scene only
// describes it; render/mesh_file.h load_scene_mesh reads the file (which must
// hold a closed mesh). p_world = world_from_mesh (scale p_file) + position_mm.
struct MeshSolid {
  std::string file;         // the mesh file as resolved by the reader
  MeshPlacement placement;  // scale (file units -> mm), rotation, position
  MeshLoadOptions options;  // normals (flat, smooth, file) and the crease angle of smooth ones
  std::string material;
  std::string field;
};

enum class Lattice { sc, bcc, fcc };
const char* lattice_name(Lattice lattice);
// "sc", "bcc", "fcc"; std::nullopt otherwise.
std::optional<Lattice> lattice_from_name(const std::string& name);

// A regular packing of equal spheres, expanded into spheres by render/packing.h.
// Layers are square grids in planes of constant world z, stacked along +z.
// Layer 0 has layer_size[0] x layer_size[1] spheres at
// origin_mm + (i * pitch, j * pitch, 0); odd layers of bcc and fcc are shifted by
// (pitch/2, pitch/2) and keep the (nx-1) x (ny-1) sites inside the first layer's
// footprint; sc layers are all nx x ny.
struct PackingOverride {
  // Exactly one selector: a sphere [layer, i, j] or a box region holding the sphere centre.
  std::optional<std::array<int, 3>> sphere;
  std::optional<std::array<Eigen::Vector3d, 2>> region_mm;  // min, max corners
  std::string material;
  std::string field;
};

struct Packing {
  Lattice lattice = Lattice::bcc;
  double diameter_mm = 0;
  int layers = 1;
  std::array<int, 2> layer_size{1, 1};
  Eigen::Vector3d origin_mm = Eigen::Vector3d::Zero();  // centre of sphere (layer 0, i 0, j 0)
  std::string material;
  std::vector<PackingOverride> overrides;  // later entries win
  std::string field;
};

// The laser sheet: a rectangle centred on origin_mm, s in [-extent_s/2, extent_s/2]
// along s_axis, t likewise; normal = s_axis x t_axis. The intensity profile across
// it is Gaussian; thickness_mm is its full width at 1/e^2 of the peak (2 w).
struct Sheet {
  Eigen::Vector3d origin_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d s_axis = Eigen::Vector3d::UnitX();
  Eigen::Vector3d t_axis = Eigen::Vector3d::UnitY();
  std::array<double, 2> extent_mm{0, 0};
  double thickness_mm = 1;

  Eigen::Vector3d normal() const { return s_axis.cross(t_axis); }
  // The Gaussian's standard deviation: thickness / 4 (1/e^2 full width = 4 sigma).
  double sigma_mm() const { return thickness_mm / 4.0; }
  double fwhm_mm() const;
};

struct Background {
  double radiance = 0;
};

struct SceneCamera {
  std::string name;
  std::string file;  // the camera file as resolved by the reader ("" for an inline model)
  Camera camera;     // camera_from_world always set
  std::string field;
};

struct Scene {
  std::string source;  // the file it was read from ("" when built in code); errors name it
  double wavelength_nm = 532;
  std::string fluid = "air";
  std::map<std::string, Material> materials;  // the scene's own names; catalogue names need no entry
  std::vector<SphereSolid> spheres;
  std::vector<BoxSolid> boxes;
  std::vector<SlabSolid> slabs;
  std::vector<CylinderSolid> cylinders;
  std::vector<RectangleSolid> rectangles;
  std::vector<MeshSolid> meshes;  // from `meshes:` and `solids: - type: mesh`, in file order within each
  std::vector<Packing> packings;
  std::optional<Sheet> sheet;
  Background background;
  std::vector<SceneCamera> cameras;

  // The material of a name: the scene's own first, then the catalogue. Throws
  // InputError(source, field, "unknown material ...") otherwise.
  Material material(const std::string& name, const std::string& field = "material") const;
  // The explicit spheres followed by every packing's spheres. check_solid_count
  // first: InputError beyond kMaxSceneSolids, before anything is expanded.
  std::vector<SphereSolid> all_spheres() const;
};

// The limits every scene is held to (validate() refuses anything beyond them,
// naming the field and the limit). Coordinates in mm (solid centres and points,
// mesh positions, packing sites, override regions, the sheet's origin, camera
// positions) lie within +-kMaxSceneCoordinate_mm of the origin on every axis;
// sizes in mm (diameters, radii, lengths, box sizes, extents, thicknesses) in
// [kMinSceneSize_mm, kMaxSceneSize_mm]. A scene holds at most kMaxSceneSolids
// solids, the spheres its packings expand to included (counted before any
// packing is expanded), and a packing at most kMaxPackingOverrides overrides.
constexpr double kMaxSceneCoordinate_mm = 1e6;  // 1 km
constexpr double kMinSceneSize_mm = 1e-3;       // 1 um
constexpr double kMaxSceneSize_mm = 1e6;
constexpr std::size_t kMaxSceneSolids = 100000;
constexpr std::size_t kMaxPackingOverrides = 1000;
// wavelength_nm lies in [kMinWavelength_nm, kMaxWavelength_nm]; a constant
// refractive index ({index: n}) in [kMinRefractiveIndex, kMaxRefractiveIndex]
// (vacuum relative to air is 0.9997); absorption_per_mm in [0, kMaxAbsorption_per_mm];
// background.radiance in [0, kMaxBackgroundRadiance]; a mesh's scale in
// [kMinMeshScale, kMaxMeshScale].
constexpr double kMinWavelength_nm = 100;
constexpr double kMaxWavelength_nm = 20000;
constexpr double kMinRefractiveIndex = 0.5;
constexpr double kMaxRefractiveIndex = 10;
constexpr double kMaxAbsorption_per_mm = 1e6;
constexpr double kMaxBackgroundRadiance = 1e6;
constexpr double kMinMeshScale = 1e-6;
constexpr double kMaxMeshScale = 1e6;

// Throws InputError(scene.source, field, problem) unless the scene holds at most
// kMaxSceneSolids solids, counting the spheres of every packing without
// expanding it (the field names the packing or solid list that goes over).
void check_solid_count(const Scene& scene);

// Checks what the data alone can tell, throwing InputError(scene.source, field path,
// problem) at the first fault: the limits above, positive sizes, unit and non-zero axes, orthonormal
// sheet axes, known materials (fluid not opaque), refractive indices defined at the
// wavelength, packing overrides that select something, no two spheres overlapping by
// more than 1e-6 mm (touching is fine), unique camera names, cameras with a pose,
// meshes with a file name, a positive scale and a rotation (their files are not
// read here: load_scene_mesh does that).
void validate(const Scene& scene);

// Tolerances of the axes: a direction whose length is within kAxisLengthTolerance
// of 1 is normalised; sheet axes whose normalised dot product is within
// kAxisOrthogonalityTolerance of 0 are made exactly orthogonal (t re-orthogonalised
// against s). Anything further off is an error. The reader applies this.
constexpr double kAxisLengthTolerance = 1e-3;
constexpr double kAxisOrthogonalityTolerance = 1e-4;
constexpr double kSphereOverlapTolerance_mm = 1e-6;

// camera_from_world of a camera at position_mm looking at look_at_mm, with `up`
// (any vector not parallel to the view direction) appearing upwards in the image,
// i.e. along -y. Throws InputError(file "", field "pose", ...) if degenerate.
RigidTransform camera_from_world_look_at(const Eigen::Vector3d& position_mm, const Eigen::Vector3d& look_at_mm,
                                         const Eigen::Vector3d& up);

// Rotation from degrees: an axis-angle vector in degrees, or DaVis-order Euler angles
// R = Rz * Ry * Rx in degrees.
Eigen::Matrix3d rotation_from_rvec_deg(const Eigen::Vector3d& rvec_deg);
Eigen::Matrix3d rotation_from_euler_deg(const Eigen::Vector3d& euler_deg);

}  // namespace glasspiv
