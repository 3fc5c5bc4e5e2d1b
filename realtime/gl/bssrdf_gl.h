// BSSRDF Explorer's .bssrdf files [Bitterli13 §A.2] evaluated where the paper evaluates them: the
// GLSL sections (initializer, diffuseReflectance, shader; approx/bssrdf_file.h reads and checks
// the rest) pieced together with the application's code into a fragment shader and run in the GL
// twin's headless context (OSMesa or EGL, context.h). The application's names are uniforms:
// `vec3 SigmaA`, `vec3 SigmaS` [1/L], `float G`, `float IOR`, and `const float PI`; each parameter
// is a uniform of its type (float, bool, vec3 for color). `init()` runs before the evaluations (in
// every fragment, which is the same for code without side effects), `Bssrdf(Xi, Wi, Xo, Wo)` per
// radius with Xi = (r, 0, 0), Xo = 0 and Wi = Wo = (0, 0, 1), the surface normal (the pencil
// beam's incidence; a file must be `radial` and `no_wo`: R_d is the exitance, which a BSSRDF that
// depends on Wo gives only through an integral over Wo).
//
// A channel of the medium is evaluated with that channel's coefficients in all three components
// of SigmaA and SigmaS and the parameters' own values (a color's three), and the result's
// component of that channel is taken: for code that works component by component, as the paper's
// files do, the channel's value. Arithmetic is the GPU's float: expect float accuracy.
#pragma once

#include "approx/bssrdf_file.h"
#include "approx/diffusion.h"
#include "realtime/gl/context.h"

#include <array>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace ssslab::realtime::gl {

/// What one evaluation gives for one channel.
struct BssrdfValues {
    std::vector<double> rd;  ///< Bssrdf() at each radius [1/L^2]
    /// DiffuseReflectance(alpha') of the medium's reduced albedo, where the file has the section.
    std::optional<double> diffuse_reflectance;
};

/// Parameter values by name: a float's or bool's value in [0], a color's RGB; absent ones take
/// their default.
using BssrdfParameterValues = std::map<std::string, std::array<double, 3>>;

/// Checks that `file` is a radial profile (approx::require_radial_profile) and that its GLSL
/// compiles, in a context of `platform` made and released for it (a context that was current on
/// this thread must be made current again): InputError at the file's line with the compiler's
/// message, std::runtime_error saying why no context could be made.
void check_bssrdf(const approx::BssrdfFile& file, GlPlatform platform = GlPlatform::kAuto);

/// Evaluates `file` for channel `channel` (0-2) of medium `m` at `radii` [L] on the current GL
/// context (OpenGL 3.3 core). Throws InputError at the file's line with the compiler's
/// message when the GLSL does not compile (also for a file that is not radial and no_wo, at its
/// first line), std::invalid_argument for an unknown parameter or a value outside its range
/// (naming the file and the parameter), and std::runtime_error when a value is not finite.
BssrdfValues evaluate_bssrdf(const approx::BssrdfFile& file, const approx::DiffusionMedium& m,
                             int channel, const std::vector<double>& radii,
                             const BssrdfParameterValues& values = {});

/// The profile of `file` for channel `channel` of `m`: Bssrdf() tabulated through GL at
/// kBssrdfTableRadii radii from 1e-6 to 1e6 reduced mean free paths and interpolated
/// (approx::TabulatedProfile); the model is named `name`. Makes a context of `platform` for the
/// evaluation and releases it (std::runtime_error saying why none could be made): a context
/// that was current on this thread must be made current again. Errors as evaluate_bssrdf.
std::unique_ptr<approx::DiffusionProfile> make_bssrdf_profile(
    const approx::BssrdfFile& file, const std::string& name, const approx::DiffusionMedium& m,
    int channel, const BssrdfParameterValues& values = {}, GlPlatform platform = GlPlatform::kAuto);

/// 2048 radii a decade over the table's 12 decades.
inline constexpr int kBssrdfTableRadii = 12 * 2048 + 1;

}  // namespace ssslab::realtime::gl
