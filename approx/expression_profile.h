// A radial profile written as expressions in a TOML file, evaluated on the CPU by muparser (for
// machines without GL; the .bssrdf files of BSSRDF Explorer [Bitterli13 §A.2] are the other way,
// approx/bssrdf_file.h). A researcher adds a profile model without a rebuild:
//
//   # experiments/bssrdf/dipole.toml: the classical dipole [Jensen01; Bitterli13 Eq. 2.33-2.37]
//   [profile]
//   single_scattering = false
//   init = [                      # evaluated once per medium, in order: "name = expression"
//     "sigma_tr = sqrt(3 * sigma_a * sigma_t_r)",
//     ...
//   ]
//   rd = "alpha_r / (4 * pi) * (...)"   # R_d(r) [1/L^2] per unit power entering
//   total_rd = "..."                    # optional: R_dr; else 2 pi int R_d r dr numerically
//   [[parameter]]
//   name = "Multiplier"
//   min = 0.0
//   max = 10.0
//   default = 1.0
//
// Names the expressions may use: r (in rd only), the medium's sigma_a, sigma_s, g, eta and
// sigma_s_r = sigma_s (1 - g), sigma_t_r = sigma_a + sigma_s_r, alpha_r = sigma_s_r / sigma_t_r,
// pi, the parameters, and the init names defined before; any unit of length L, the medium's.
// Functions: muparser's (exp, sqrt, ln, sin, ..., min, max, the ternary a ? b : c) and expm1.
#pragma once

#include "approx/diffusion.h"

#include <map>
#include <memory>
#include <string>
#include <vector>

namespace ssslab::approx {

/// A parsed expression-profile file (expressions checked for syntax and names).
struct ExpressionProfileDef {
    struct Parameter {
        std::string name;
        double min = 0, max = 0, fallback = 0;
    };
    struct Definition {
        std::string name, expression;
    };
    std::string path;  ///< the file, for messages
    std::string text;  ///< the file's content: what keys a cache entry of results that use it
    std::string name;  ///< the model's name: the file's stem
    bool single_scattering = false;
    std::vector<Parameter> parameters;
    std::vector<Definition> init;
    Definition rd, total_rd;  ///< total_rd.expression empty: integrated numerically
};

/// Reads an expression-profile file. Throws InputError naming the file, line and key for TOML
/// errors, unknown keys, a bad parameter (a name that is not an identifier or that the
/// application defines, min > max, a default outside [min, max]), and an expression that does not
/// parse or uses an unknown name (muparser's message, the position in the expression).
ExpressionProfileDef read_expression_profile(const std::string& path);
/// The same from text; `path` names it in messages.
ExpressionProfileDef parse_expression_profile(const std::string& text, const std::string& path);

/// The profile of a medium: parameter values by name (each in its range; absent ones take their
/// default). Throws std::invalid_argument for an unknown parameter or a value outside its range
/// (naming the file and the parameter), or a medium that fails validate(m, fit).
std::unique_ptr<DiffusionProfile> make_expression_profile(
    const ExpressionProfileDef& def, const DiffusionMedium& m,
    const std::map<std::string, double>& values = {});

}  // namespace ssslab::approx
