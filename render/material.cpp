#include "render/material.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "util/input_error.h"

namespace glasspiv {

double Dispersion::evaluate_um(double lambda_um) const {
  const double l2 = lambda_um * lambda_um;
  switch (formula) {
    case Formula::constant:
      return b.at(0);
    case Formula::sellmeier: {
      double n2 = 1.0;
      for (size_t i = 0; i < b.size(); ++i) n2 += b[i] * l2 / (l2 - c[i]);
      return std::sqrt(n2);
    }
    case Formula::cauchy: {
      double n = 0.0, inv_l2k = 1.0;
      for (double a : b) {
        n += a * inv_l2k;
        inv_l2k /= l2;
      }
      return n;
    }
    case Formula::gas: {
      const double sigma2 = 1.0 / l2;  // wavenumber squared, um^-2
      double n_minus_1 = 0.0;
      for (size_t i = 0; i < b.size(); ++i) n_minus_1 += b[i] / (c[i] - sigma2);
      return 1.0 + n_minus_1;
    }
  }
  throw std::logic_error("Dispersion: unknown formula");
}

double Material::refractive_index(double wavelength_nm) const {
  if (kind == MaterialKind::opaque) throw std::logic_error("material '" + name + "' is opaque and has no refractive index");
  if (!(wavelength_nm >= dispersion.min_wavelength_nm && wavelength_nm <= dispersion.max_wavelength_nm) ||
      !(wavelength_nm > 0.0)) {
    std::ostringstream s;
    s << "wavelength " << wavelength_nm << " nm is outside the range of " << name << "'s dispersion formula ("
      << dispersion.min_wavelength_nm << " to " << dispersion.max_wavelength_nm << " nm)";
    throw InputError("", "wavelength_nm", s.str());
  }
  const double n = dispersion.evaluate_um(wavelength_nm * 1e-3);
  return dispersion.relative_to_air ? n * standard_air_index(wavelength_nm) : n;
}

double Material::index_relative_to_air(double wavelength_nm) const {
  const double n = refractive_index(wavelength_nm);
  return dispersion.relative_to_air ? dispersion.evaluate_um(wavelength_nm * 1e-3) : n / standard_air_index(wavelength_nm);
}

namespace {

// Ciddor (1996) standard air: n - 1 = B1 / (C1 - s^2) + B2 / (C2 - s^2), s = 1/lambda in um^-1.
constexpr double kAirB[2] = {0.05792105, 0.00167917};
constexpr double kAirC[2] = {238.0185, 57.362};  // um^-2
constexpr double kAirMinNm = 230.0, kAirMaxNm = 1690.0;

}  // namespace

double standard_air_index(double wavelength_nm) {
  const double lambda_um = std::clamp(wavelength_nm, kAirMinNm, kAirMaxNm) * 1e-3;
  const double s2 = 1.0 / (lambda_um * lambda_um);
  return 1.0 + kAirB[0] / (kAirC[0] - s2) + kAirB[1] / (kAirC[1] - s2);
}

namespace {

Material sellmeier(std::string name, MaterialKind kind, std::vector<double> b, std::vector<double> c, double min_nm,
                   double max_nm, std::string source) {
  Material m;
  m.name = std::move(name);
  m.kind = kind;
  m.dispersion.formula = Dispersion::Formula::sellmeier;
  m.dispersion.b = std::move(b);
  m.dispersion.c = std::move(c);
  m.dispersion.min_wavelength_nm = min_nm;
  m.dispersion.max_wavelength_nm = max_nm;
  m.dispersion.source = std::move(source);
  return m;
}

double sq(double x) { return x * x; }

Material n_bk7() {
  // SCHOTT optical glass datasheet N-BK7 (517642.251): Sellmeier B1..B3, C1..C3 (um^2),
  // nd = 1.51680, nF = 1.52238, nC = 1.51432, nu_d = 64.17; data 0.3-2.5 um.
  return sellmeier("N-BK7", MaterialKind::glass, {1.03961212, 0.231792344, 1.01046945},
                   {0.00600069867, 0.0200179144, 103.560653}, 300.0, 2500.0,
                   "SCHOTT optical glass datasheet N-BK7 (Sellmeier coefficients)");
}

Material fused_silica() {
  // I. H. Malitson, "Interspecimen comparison of the refractive index of fused
  // silica", J. Opt. Soc. Am. 55, 1205-1209 (1965), at 20 C, fitted 0.21-3.71 um.
  return sellmeier("fused_silica", MaterialKind::glass, {0.6961663, 0.4079426, 0.8974794},
                   {sq(0.0684043), sq(0.1162414), sq(9.896161)}, 210.0, 3710.0,
                   "Malitson, J. Opt. Soc. Am. 55, 1205 (1965)");
}

Material borofloat33() {
  // SCHOTT BOROFLOAT 33 datasheet: nd = 1.47140 (587.6 nm), Abbe number
  // nu_d = 65.41. SCHOTT publishes no Sellmeier fit for it, so we use the
  // two-term Cauchy law n = A + B / lambda^2 through these two numbers:
  //   B = (nd - 1) / (nu_d (1/lambda_F^2 - 1/lambda_C^2)),  A = nd - B / lambda_d^2.
  // It reproduces nd and nu_d exactly; elsewhere in the visible it is good to a
  // few 1e-4 (typical of a two-term Cauchy for a crown glass). Kept to 400-800 nm.
  const double nd = 1.47140, nu_d = 65.41;
  const double inv_d = 1.0 / sq(kWavelengthD_nm * 1e-3), inv_f = 1.0 / sq(kWavelengthF_nm * 1e-3),
               inv_c = 1.0 / sq(kWavelengthC_nm * 1e-3);
  const double b = (nd - 1.0) / (nu_d * (inv_f - inv_c));
  Material m;
  m.name = "BOROFLOAT33";
  m.kind = MaterialKind::glass;
  m.dispersion.formula = Dispersion::Formula::cauchy;
  m.dispersion.b = {nd - b * inv_d, b};
  m.dispersion.min_wavelength_nm = 400.0;
  m.dispersion.max_wavelength_nm = 800.0;
  m.dispersion.source = "SCHOTT BOROFLOAT 33 datasheet (nd = 1.47140, nu_d = 65.41), two-term Cauchy fit";
  return m;
}

Material pmma() {
  // N. Sultanova, S. Kasarova, I. Nikolov, "Dispersion properties of optical
  // polymers", Acta Physica Polonica A 116, 585-587 (2009), one-term Sellmeier
  // as given by refractiveindex.info (Szczurowski), 0.4368-1.052 um, 20 C.
  return sellmeier("PMMA", MaterialKind::glass, {1.1819}, {0.011313}, 436.8, 1052.0,
                   "Sultanova et al., Acta Phys. Pol. A 116, 585 (2009)");
}

Material water() {
  // M. Daimon, A. Masumura, "Measurement of the refractive index of distilled
  // water from the near-infrared region to the ultraviolet region", Appl. Opt.
  // 46, 3811-3820 (2007): four-term Sellmeier at 20.0 C, 0.182-1.129 um.
  // Their indices are absolute (vacuum): 1.33335 at 589.3 nm, i.e. 1.33299
  // relative to air, the handbook nD of water at 20 C.
  Material m = sellmeier("water", MaterialKind::fluid, {5.684027565e-1, 1.726177391e-1, 2.086189578e-2, 1.130748688e-1},
                         {5.101829712e-3, 1.821153936e-2, 2.620722293e-2, 1.069792721e1}, 182.0, 1129.0,
                         "Daimon & Masumura, Appl. Opt. 46, 3811 (2007), 20 C, absolute index");
  m.dispersion.relative_to_air = false;
  return m;
}

Material air() {
  // P. E. Ciddor, "Refractive index of air: new equations for the visible and
  // near infrared", Appl. Opt. 35, 1566-1573 (1996): standard air, 15 C,
  // 101 325 Pa, dry, 450 ppm CO2: n - 1 = 0.05792105 / (238.0185 - s^2)
  // + 0.00167917 / (57.362 - s^2), s = 1/lambda in um^-1, 0.23-1.69 um.
  Material m;
  m.name = "air";
  m.kind = MaterialKind::fluid;
  m.dispersion.formula = Dispersion::Formula::gas;
  m.dispersion.b = {kAirB[0], kAirB[1]};
  m.dispersion.c = {kAirC[0], kAirC[1]};
  m.dispersion.min_wavelength_nm = kAirMinNm;
  m.dispersion.max_wavelength_nm = kAirMaxNm;
  m.dispersion.relative_to_air = false;
  m.dispersion.source = "Ciddor, Appl. Opt. 35, 1566 (1996), standard air 15 C, 101325 Pa, 450 ppm CO2";
  return m;
}

std::string normalized(const std::string& name) {
  std::string out;
  for (char ch : name)
    if (ch != '-' && ch != '_' && ch != ' ') out += static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  return out;
}

}  // namespace

std::vector<std::string> material_names() {
  return {"N-BK7", "fused_silica", "BOROFLOAT33", "PMMA", "water", "air", "polypropylene"};
}

Material material_from_name(const std::string& name) {
  const std::string key = normalized(name);
  if (key == "nbk7" || key == "bk7") return n_bk7();
  if (key == "fusedsilica") return fused_silica();
  if (key == "borofloat33" || key == "borosilicate") return borofloat33();
  if (key == "pmma" || key == "acrylic") return pmma();
  if (key == "water") return water();
  if (key == "air") return air();
  if (key == "polypropylene") {
    // A commonly quoted nd for polypropylene; its dispersion is not modelled.
    Material m = material_with_index("polypropylene", 1.49, MaterialKind::glass);
    m.dispersion.source = "constant index 1.49 (typical nd of polypropylene)";
    return m;
  }
  std::string known;
  for (const auto& n : material_names()) known += (known.empty() ? "" : ", ") + n;
  throw InputError("", "material", "unknown material '" + name + "' (known: " + known + ")");
}

Material material_with_index(std::string name, double n, MaterialKind kind) {
  if (!(n > 0.0) || !std::isfinite(n))
    throw InputError("", "refractive_index", "refractive index of '" + name + "' must be a finite number > 0");
  Material m;
  m.name = std::move(name);
  m.kind = kind;
  m.dispersion.formula = Dispersion::Formula::constant;
  m.dispersion.b = {n};
  m.dispersion.min_wavelength_nm = 0.0;
  m.dispersion.max_wavelength_nm = std::numeric_limits<double>::infinity();
  m.dispersion.source = "constant index";
  return m;
}

Material opaque_material(std::string name, double albedo) {
  if (!(albedo >= 0.0 && albedo <= 1.0))
    throw InputError("", "albedo", "albedo of '" + name + "' must lie in [0, 1]");
  Material m;
  m.name = std::move(name);
  m.kind = MaterialKind::opaque;
  m.albedo = albedo;
  return m;
}

double abbe_number(const Material& material) {
  const double nd = material.index_relative_to_air(kWavelengthD_nm);
  return (nd - 1.0) /
         (material.index_relative_to_air(kWavelengthF_nm) - material.index_relative_to_air(kWavelengthC_nm));
}

}  // namespace glasspiv
