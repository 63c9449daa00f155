#pragma once
// Optical materials by catalogue name: a refractive index as a function of the
// wavelength from a published dispersion formula, with the
// formula's range of validity, and optional absorption (Beer-Lambert) or, for
// opaque surfaces, an albedo. The catalogue, its sources and its conventions are
// documented in docs/materials.md.
//
// Dispersion formulas, wavelength lambda in micrometres:
//   Sellmeier:  n^2(lambda) = 1 + sum_i B_i lambda^2 / (lambda^2 - C_i)      (C_i in um^2)
//   Cauchy:     n(lambda)   = A_0 + A_1 / lambda^2 + A_2 / lambda^4 + ...    (A_k in um^(2k))
//   gas:        n(lambda) - 1 = sum_i B_i / (C_i - lambda^-2)               (C_i in um^-2;
//               the form of Ciddor's 1996 standard-air fit)
//   constant:   n(lambda) = n
// Index scale: Material::refractive_index is the *absolute* index (relative to
// vacuum), so that any two materials can be put into Snell's law. Glass and
// polymer catalogues quote indices relative to air (SCHOTT, Malitson, handbook
// nd values); those formulas are flagged relative_to_air and multiplied by the
// index of standard air (Ciddor 1996, the "air" entry) at the same wavelength.
// Daimon & Masumura's water fit and Ciddor's air are absolute already. The
// difference is ~2.8e-4 in n, i.e. the gap between water's absolute 1.33335 and
// the handbook's nD = 1.33299 (relative to air) at 20 C.
// Wavelengths are taken as given by each source (air wavelengths for the
// catalogues); the air/vacuum wavelength difference (2.8e-4 relative) moves n by
// < 1e-5 in the visible and is neglected.
#include <optional>
#include <string>
#include <vector>

namespace glasspiv {

enum class MaterialKind { glass, fluid, opaque };

struct Dispersion {
  enum class Formula { constant, sellmeier, cauchy, gas };
  Formula formula = Formula::constant;
  std::vector<double> b;  // constant: {n}; Sellmeier/gas: B_i; Cauchy: A_0, A_1, ...
  std::vector<double> c;  // Sellmeier: C_i (um^2); gas: C_i (um^-2); else empty
  double min_wavelength_nm = 0;  // the range the formula was fitted over
  double max_wavelength_nm = 0;  // (constant: any wavelength, max = +inf)
  bool relative_to_air = true;   // the formula gives n relative to air (catalogue convention)
  std::string source;            // the publication or datasheet the numbers come from

  // The formula at lambda_um, without the range check.
  double evaluate_um(double lambda_um) const;
};

struct Material {
  std::string name;
  MaterialKind kind = MaterialKind::glass;
  Dispersion dispersion;                   // unused for opaque materials
  std::optional<double> absorption_per_mm;  // natural-log attenuation coefficient; none = not modelled
  std::optional<double> albedo;             // opaque only: diffuse reflectance in [0, 1]

  // Absolute n (relative to vacuum) at the given wavelength in nm. Throws InputError (file "", field
  // "wavelength_nm") outside the formula's range of validity, and
  // std::logic_error for an opaque material, which has no index.
  double refractive_index(double wavelength_nm) const;

  // n relative to standard air, the value glass catalogues quote (1 for air).
  double index_relative_to_air(double wavelength_nm) const;
};

// Absolute index of standard air (Ciddor 1996, 15 C, 101 325 Pa, dry, 450 ppm
// CO2) with the wavelength clamped to the fit's range 230-1690 nm (outside it
// n - 1 changes by < 2e-6 towards the infrared); used to put catalogue indices
// on the absolute scale.
double standard_air_index(double wavelength_nm);

// The catalogue's canonical names: "N-BK7", "fused_silica", "BOROFLOAT33",
// "PMMA", "water", "air", "polypropylene".
std::vector<std::string> material_names();

// Looks up a catalogue material. Matching ignores case, '-', '_' and spaces
// ("n_bk7", "Fused Silica"); aliases: "BK7" -> N-BK7, "borosilicate" ->
// BOROFLOAT33, "acrylic" -> PMMA. Throws InputError(file "", field "material",
// "unknown material 'x' (known: ...)") for anything else.
Material material_from_name(const std::string& name);

// A material with a constant index n > 0 at every wavelength ("by index"),
// taken relative to air like a handbook nd.
Material material_with_index(std::string name, double n, MaterialKind kind = MaterialKind::glass);

// An opaque surface with a diffuse albedo in [0, 1].
Material opaque_material(std::string name, double albedo);

// Fraunhofer/helium lines used for catalogue indices and the Abbe number (nm).
constexpr double kWavelengthD_nm = 587.5618;  // He d line
constexpr double kWavelengthF_nm = 486.1327;  // H F line
constexpr double kWavelengthC_nm = 656.2725;  // H C line

// Abbe number nu_d = (n_d - 1) / (n_F - n_C), the catalogue's measure of
// dispersion, from indices relative to air as catalogues compute it.
double abbe_number(const Material& material);

}  // namespace glasspiv
