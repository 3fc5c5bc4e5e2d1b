// .bssrdf files evaluated through the GL twin (realtime/gl/bssrdf_gl.h) [Bitterli13 §A.2]: the
// paper's Listing A.2 against approx's classical dipole to float accuracy, its
// DiffuseReflectance against the dipole's closed-form R_dr, parameters as uniforms, the tabulated
// profile the scoring uses, and bad files refused at their lines with the compiler's message.
// Skipped where no OpenGL context can be made.
#include "approx/bssrdf_file.h"
#include "approx/diffusion.h"
#include "core/error.h"
#include "realtime/gl/bssrdf_gl.h"
#include "realtime/gl/context.h"
#include "tests/testing.h"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>

using namespace ssslab;
using realtime::gl::GlContext;

namespace {

// One context for the program (llvmpipe's start-up is not free), current on the test's thread.
GlContext* context() {
    static std::string why;
    static std::unique_ptr<GlContext> c =
        realtime::gl::try_gl_context(realtime::gl::GlPlatform::kAuto, why);
    if (c) c->make_current();
    return c.get();
}

#define REQUIRE_GL() \
    if (!context()) GTEST_SKIP() << "no OpenGL context"

approx::BssrdfFile listing_a2() {
    return approx::read_bssrdf(ssslab::testing::source_path("experiments/bssrdf/dipole.bssrdf"));
}

// Listing A.2 with line `line` (from 1) replaced by `text`.
approx::BssrdfFile listing_with(int line, const std::string& text) {
    const approx::BssrdfFile f = listing_a2();
    std::string all = ssslab::testing::read_text(
        ssslab::testing::source_path("experiments/bssrdf/dipole.bssrdf"));
    std::string out;
    size_t pos = 0;
    for (int k = 1; pos <= all.size(); ++k) {
        const size_t end = all.find('\n', pos);
        const std::string l =
            all.substr(pos, end == std::string::npos ? std::string::npos : end - pos);
        out += (k == line ? text : l) + "\n";
        if (end == std::string::npos) break;
        pos = end + 1;
    }
    return approx::parse_bssrdf(out, "edited.bssrdf");
}

InputError compile_error_of(const approx::BssrdfFile& f) {
    return ssslab::testing::input_error_of(
        [&] {
            realtime::gl::evaluate_bssrdf(f, {0.1, 1.0, 0.0, 1.3}, 0, {1.0});
        },
        f.path);
}

}  // namespace

// Float accuracy, stated: the shader's arithmetic is float (unit round-off u = 2^-24); the
// exponent sigma_tr d carries a relative error of a few u, so e^{-sigma_tr d} one of a few
// u (1 + sigma_tr d). The bound allows 32 u (2 + sigma_tr d_v).
TEST(BssrdfGl, ListingA2EqualsTheDipoleToFloatAccuracy) {
    REQUIRE_GL();
    const approx::BssrdfFile f = listing_a2();
    const double u = std::ldexp(1.0, -24);
    for (const double albedo : {0.01, 0.5, 0.99, 0.999999})
        for (const double g : {-0.9, 0.0, 0.9})
            for (const double eta : {1.0, 1.3, 2.5})  // Listing A.2's Fdr is the eta >= 1 fit
                for (const double sigma_t : {1e-3, 1.0, 1e4}) {
                    const approx::DiffusionMedium m{(1 - albedo) * sigma_t, albedo * sigma_t, g,
                                                    eta};
                    const auto dipole = approx::make_diffusion_profile("dipole", m);
                    const double l = 1 / m.sigma_t_reduced();
                    const double tr = std::sqrt(3 * m.sigma_a * m.sigma_t_reduced());
                    std::vector<double> radii;
                    for (double x = 1e-4; x < 1e3; x *= 1.7) radii.push_back(x * l);
                    for (int c = 0; c < 3; ++c) {
                        const auto v = realtime::gl::evaluate_bssrdf(f, m, c, radii);
                        for (size_t k = 0; k < radii.size(); ++k) {
                            const double want = dipole->rd(radii[k]);
                            const double zv =
                                l * (1 + 4.0 / 3.0 *
                                             (1 + approx::fresnel_diffuse_reflectance(
                                                      eta, approx::FresnelMoments::fit)) /
                                             (1 - approx::fresnel_diffuse_reflectance(
                                                      eta, approx::FresnelMoments::fit)));
                            const double x = tr * std::hypot(radii[k], zv);
                            if (x > 80 || want < 1e-30) continue;  // float's exponent range
                            EXPECT_NEAR(v.rd[k] / want, 1.0, 32 * u * (2 + x))
                                << "albedo " << albedo << " g " << g << " eta " << eta
                                << " sigma_t " << sigma_t << " r/l " << radii[k] / l;
                        }
                        ASSERT_TRUE(v.diffuse_reflectance);
                        // The listing's sqrt(3 (1 - alpha')) takes 1 - alpha' from a float
                        // alpha': an error of u / sqrt(1 - alpha') in the exponent.
                        const double a = m.sigma_s_reduced() / m.sigma_t_reduced();
                        EXPECT_NEAR(*v.diffuse_reflectance / dipole->total_rd(), 1.0,
                                    64 * u * (1 + 1 / std::sqrt(1 - a)))
                            << albedo << " " << g << " " << eta;
                    }
                }
}

TEST(BssrdfGl, ParametersAreUniforms) {
    REQUIRE_GL();
    const approx::BssrdfFile f = listing_a2();
    const approx::DiffusionMedium m{0.1, 2.0, 0.3, 1.3};
    const std::vector<double> radii = {0.01, 0.3, 2.0};
    const auto one = realtime::gl::evaluate_bssrdf(f, m, 1, radii);
    const auto three = realtime::gl::evaluate_bssrdf(f, m, 1, radii, {{"Multiplier", {3, 0, 0}}});
    for (size_t k = 0; k < radii.size(); ++k) EXPECT_FLOAT_EQ(three.rd[k], 3 * one.rd[k]);
    EXPECT_THROW(realtime::gl::evaluate_bssrdf(f, m, 1, radii, {{"Multiplier", {11, 0, 0}}}),
                 std::invalid_argument);
    EXPECT_THROW(realtime::gl::evaluate_bssrdf(f, m, 1, radii, {{"Gain", {1, 0, 0}}}),
                 std::invalid_argument);
    // A color is a vec3 whose channel's component is taken; a bool is a bool.
    const approx::BssrdfFile c = approx::parse_bssrdf(
        "analytic radial no_wi no_wo\n::begin parameters\ncolor Tint 0.25 0.5 2.0\nbool Off false\n"
        "::end parameters\n::begin shader\nvec3 Bssrdf(vec3 Xi, vec3 Wi, vec3 Xo, vec3 Wo) {\n"
        "  return Off ? vec3(0.0) : Tint * SigmaA;\n}\n::end shader\n",
        "tint.bssrdf");
    const double tint[3] = {0.25, 0.5, 2.0};
    for (int ch = 0; ch < 3; ++ch) {
        const double got = realtime::gl::evaluate_bssrdf(c, m, ch, {1.0}).rd[0];
        EXPECT_FLOAT_EQ(got, tint[ch] * 0.1f);
    }
    EXPECT_EQ(realtime::gl::evaluate_bssrdf(c, m, 0, {1.0}, {{"Off", {1, 0, 0}}}).rd[0], 0.0);
}

TEST(BssrdfGl, TheTabulatedProfileScoresLikeTheDipole) {
    REQUIRE_GL();
    const approx::DiffusionMedium m{0.05, 3.0, 0.8, 1.4};
    const auto dipole = approx::make_diffusion_profile("dipole", m);
    const auto p = realtime::gl::make_bssrdf_profile(listing_a2(), "dipole.bssrdf", m, 2);
    context();  // make_bssrdf_profile made and released its own context
    EXPECT_EQ(p->name(), "dipole.bssrdf");
    const double l = 1 / m.sigma_t_reduced();
    for (const double r0 : {0.0, 0.5 * l, 4 * l, 20 * l})
        EXPECT_NEAR(p->annulus_mean(r0, r0 + l) / dipole->annulus_mean(r0, r0 + l), 1.0, 1e-5)
            << r0;
    EXPECT_NEAR(p->total_rd() / dipole->total_rd(), 1.0, 1e-5);
}

TEST(BssrdfGl, GlslThatDoesNotCompileIsRefusedAtTheFilesLine) {
    REQUIRE_GL();
    // Line 19 of Listing A.2 is `vec3 SigmaTPrime = SigmaSPrime + SigmaA;` in init().
    const InputError init =
        compile_error_of(listing_with(19, "    vec3 SigmaTPrime = SigmaSPrme + SigmaA;"));
    EXPECT_EQ(init.where().file, "edited.bssrdf");
    EXPECT_EQ(init.where().line, 19) << init.what();
    EXPECT_NE(init.message().find("GLSL does not compile"), std::string::npos) << init.what();
    EXPECT_NE(init.message().find("SigmaSPrme"), std::string::npos) << init.what();
    // Line 48 is the shader's `return ...;`: a missing semicolon is reported there or at the
    // next line (the compiler sees the error at the next token).
    const InputError shader = compile_error_of(
        listing_with(48, "    return Multiplier/(4.0*PI)*AlphaPrime*(FluenceR + FluenceV)"));
    EXPECT_GE(shader.where().line, 48) << shader.what();
    EXPECT_LE(shader.where().line, 49) << shader.what();
    // A file that is not radial is not a profile.
    const approx::BssrdfFile f = approx::parse_bssrdf(
        "analytic no_wi no_wo\n::begin shader\nvec3 Bssrdf(vec3 Xi, vec3 Wi, vec3 Xo, vec3 Wo) "
        "{ return vec3(1.0); }\n::end shader\n",
        "plane.bssrdf");
    const InputError e = compile_error_of(f);
    EXPECT_EQ(e.where().line, 1);
    EXPECT_NE(e.message().find("radial"), std::string::npos);
    // A Bssrdf() of another signature fails in the application's call: reported at the shader
    // section's first line with the compiler's message.
    const InputError sig = compile_error_of(approx::parse_bssrdf(
        "analytic radial no_wi no_wo\n\n::begin shader\nvec3 Bssrdf(vec3 Xi) { return Xi; }\n"
        "::end shader\n",
        "signature.bssrdf"));
    EXPECT_EQ(sig.where().line, 4) << sig.what();
    EXPECT_NE(sig.message().find("Bssrdf"), std::string::npos) << sig.what();
}
