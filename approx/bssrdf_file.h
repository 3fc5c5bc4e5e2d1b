// BSSRDF Explorer's `*.bssrdf` files [Bitterli13 §A.2]: an analytic BSSRDF declared in a text
// file instead of in the application. The first line lists attributes (`analytic` mandatory;
// `radial`, `no_wi`, `no_wo`); the rest is named sections `::begin NAME` ... `::end NAME` in any
// order: `parameters` (declarations `float NAME MIN MAX DEFAULT`, `bool NAME DEFAULT`,
// `color NAME R G B`), and GLSL code in `initializer` (an `init()` run once), `diffuseReflectance`
// (`vec3 DiffuseReflectance(vec3 AlphaPrime)`, for the (R_dr, l_d) inversion) and `shader`
// (`vec3 Bssrdf(vec3 Xi, vec3 Wi, vec3 Xo, vec3 Wo)`). A section of another name is ignored, as
// the paper says. This file reads and checks the structure; the GLSL is compiled where a GL
// context exists (the OpenGL twin), and its compiler's messages are mapped back to the file's
// lines through each section's first line.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

namespace ssslab::approx {

/// A user parameter of a .bssrdf file [Bitterli13 §A.2, "Parameters Section"].
struct BssrdfParameter {
    enum class Type { kFloat, kBool, kColor };
    Type type = Type::kFloat;
    std::string name;
    double min = 0, max = 0;           ///< float only: the range a value must lie in
    std::array<double, 3> fallback{};  ///< the default: float [0], bool [0] (0 or 1), color RGB
    int line = 0;                      ///< where it is declared (from 1)
};

/// A GLSL section: its code as written and the file line of its first code line.
struct BssrdfSection {
    std::string name;
    std::string code;
    int first_line = 0;  ///< line (from 1) of the line after `::begin NAME`
};

/// A parsed .bssrdf file.
struct BssrdfFile {
    std::string path;
    std::string text;  ///< the file's content: what keys a cache entry of results that use it
    bool radial = false, no_wi = false, no_wo = false;  ///< `analytic` is required
    std::vector<BssrdfParameter> parameters;
    std::optional<BssrdfSection> initializer, diffuse_reflectance, shader;
    std::vector<std::string> ignored_sections;  ///< sections of names the paper does not define

    const BssrdfParameter* find_parameter(const std::string& name) const;
};

/// Parses the text of a .bssrdf file; `path` names it in errors. Throws InputError (file, line,
/// what is wrong, the line's text) for: a missing or unknown attribute, a missing `analytic`, text
/// outside a section, `::begin` without a name or inside a section, `::end` of another section or
/// without a `::begin`, a section without `::end`, a section given twice, a malformed parameter
/// declaration (unknown type, wrong number of values, not a number, a default outside its range,
/// a name given twice, a name that is not a GLSL identifier or is one the application defines),
/// and a file without a `shader` section.
BssrdfFile parse_bssrdf(const std::string& text, const std::string& path);

/// Throws InputError at the file's first line unless it is `radial` and `no_wo`: what a radial
/// profile model needs (R_d is the exitance at a distance, which a BSSRDF that depends on more
/// than the distance, or on Wo, gives only through integrals).
void require_radial_profile(const BssrdfFile& f);

/// Reads and parses a .bssrdf file (an IoError-free InputError if it cannot be read).
BssrdfFile read_bssrdf(const std::string& path);

/// Whether `s` is an identifier of GLSL (and of muparser): [A-Za-z_][A-Za-z0-9_]*.
bool is_glsl_identifier(const std::string& s);

/// The names the application defines for the GLSL code (uniforms of the medium, PI): a parameter
/// may not take one of them.
const std::vector<std::string>& bssrdf_reserved_names();

}  // namespace ssslab::approx
