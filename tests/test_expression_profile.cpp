// Profile models written as expressions in TOML files (approx/expression_profile): the shipped
// dipole against the built-in C++ model, parameters, numerical R_dr, and bad files.
#include "approx/diffusion.h"
#include "approx/expression_profile.h"
#include "core/error.h"
#include "tests/testing.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace ssslab;
using approx::DiffusionMedium;

namespace {

approx::ExpressionProfileDef shipped_dipole() {
    return approx::read_expression_profile(
        ssslab::testing::source_path("experiments/bssrdf/dipole.toml"));
}

InputError error_of(const std::string& text) {
    return ssslab::testing::input_error_of(
        [&] { approx::parse_expression_profile(text, "bad.toml"); }, text);
}

}  // namespace

// The shipped file against the built-in model of the same name: R_d at 18 radii per medium
// from 1e-4 to 1e3 reduced mean free paths and R_dr, over albedo 0.01-0.99999 (and 1, no
// absorption), g -0.9-0.95, eta 0.5-2.5 (both branches of the Fresnel fits), lengths over seven
// decades. Returns the number of radii compared.
static int compare_with_builtin(const std::string& file, const std::string& builtin_name,
                                double tol) {
    const approx::ExpressionProfileDef def =
        approx::read_expression_profile(ssslab::testing::source_path(file));
    EXPECT_EQ(def.name, builtin_name);
    EXPECT_FALSE(def.single_scattering);
    int compared = 0;
    for (double albedo : {0.01, 0.5, 0.9, 0.999, 0.99999, 1.0})
        for (double g : {-0.9, 0.0, 0.8, 0.95})
            for (double eta : {0.5, 0.8, 1.0, 1.3, 1.5, 2.5})
                for (double sigma_t : {1e-3, 1.0, 1e4}) {
                    const DiffusionMedium m{sigma_t * (1 - albedo), sigma_t * albedo, g, eta};
                    const auto f = approx::make_expression_profile(def, m);
                    const auto b = approx::make_diffusion_profile(builtin_name, m);
                    EXPECT_EQ(f->name(), builtin_name);
                    EXPECT_NEAR(f->total_rd(), b->total_rd(), tol * b->total_rd())
                        << file << " albedo " << albedo << " g " << g << " eta " << eta;
                    const double l = 1 / m.sigma_t_reduced();
                    for (double x = 1e-4; x < 1e3; x *= 1.7) {
                        const double u = f->rd(x * l), v = b->rd(x * l);
                        if (v < 1e-300) continue;  // both underflow
                        EXPECT_NEAR(u, v, tol * v) << file << " albedo " << albedo << " g " << g
                                                   << " eta " << eta << " r " << x * l;
                        ++compared;
                    }
                }
    return compared;
}

TEST(ExpressionProfile, ShippedDipolesEqualTheBuiltInModels) {
    EXPECT_GT(compare_with_builtin("experiments/bssrdf/dipole.toml", "dipole", 1e-12), 5000);
    EXPECT_GT(compare_with_builtin("experiments/bssrdf/better-dipole.toml", "better-dipole", 1e-12),
              5000);
}

TEST(ExpressionProfile, ParametersTakeTheirDefaultsAndTheirRanges) {
    const approx::ExpressionProfileDef def = shipped_dipole();
    const DiffusionMedium m{0.1, 10, 0.5, 1.4};
    const auto one = approx::make_expression_profile(def, m);
    const auto two = approx::make_expression_profile(def, m, {{"Multiplier", 2.0}});
    for (double r : {0.01, 0.1, 1.0}) EXPECT_DOUBLE_EQ(two->rd(r), 2 * one->rd(r));
    EXPECT_DOUBLE_EQ(two->total_rd(), 2 * one->total_rd());
    for (double bad : {-0.5, 10.5, std::nan("")}) {
        try {
            (void)approx::make_expression_profile(def, m, {{"Multiplier", bad}});
            FAIL() << bad << " accepted";
        } catch (const std::invalid_argument& e) {
            EXPECT_NE(std::string(e.what()).find("'Multiplier'"), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find("outside [0"), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find("dipole.toml"), std::string::npos) << e.what();
        }
    }
    EXPECT_THROW((void)approx::make_expression_profile(def, m, {{"Multiplyer", 1.0}}),
                 std::invalid_argument);
    EXPECT_THROW((void)approx::make_expression_profile(def, DiffusionMedium{-1, 1, 0, 1.3}),
                 std::invalid_argument);
}

TEST(ExpressionProfile, WithoutATotalTheIntegralOfTheProfileIsUsed) {
    // The dipole without its closed-form R_dr: 2 pi int R_d r dr by quadrature [JB02].
    approx::ExpressionProfileDef def = shipped_dipole();
    def.total_rd = {};
    for (double albedo : {0.3, 0.99, 0.99999}) {
        const DiffusionMedium m{1 - albedo, albedo, 0.7, 1.3};
        const double numeric = approx::make_expression_profile(def, m)->total_rd();
        const double closed = approx::make_diffusion_profile("dipole", m)->total_rd();
        EXPECT_NEAR(numeric, closed, 1e-9 * closed) << albedo;
    }
}

TEST(ExpressionProfile, BadFilesAreRefusedAtTheirLineAndKey) {
    const std::string good_rd = "rd = \"alpha_r * exp(-r)\"\n";
    struct Case {
        std::string text;
        int line;
        std::string key, says;
    } cases[] = {
        {"[profile]\nrd = \"alpha_r * exp(-sigma_x * r)\"\n", 2, "profile.rd",
         "unknown name 'sigma_x' at position 16 (did you mean 'sigma_a'?)"},
        {"[profile]\nrd = \"alpha_r * exp(-r\"\n", 2, "profile.rd", "expression 'alpha_r"},
        {"[profile]\n" + good_rd + "total_rd = \"r * 2\"\n", 3, "profile.total_rd",
         "unknown name 'r'"},
        {"[profile]\ninit = [\"k = 2\", \"h k\"]\n" + good_rd, 2, "profile.init",
         "expected 'name = expression'"},
        {"[profile]\ninit = [\"g = 2\"]\n" + good_rd, 2, "profile.init", "'g' is already defined"},
        {"[profile]\ninit = [\"k = r\"]\n" + good_rd, 2, "profile.init", "unknown name 'r'"},
        {"[profile]\ninit = [\"k = j\", \"j = 1\"]\n" + good_rd, 2, "profile.init",
         "unknown name 'j'"},
        {"[profile]\n" + good_rd + "rdd = \"1\"\n", 3, "profile.rdd", "rdd"},
        {"[profile]\nsingle_scattering = false\n", 1, "profile.rd", "rd"},
        {"[[parameter]]\nname = \"K\"\nmin = 0\nmax = 1\ndefault = 2\n[profile]\n" + good_rd, 5,
         "parameter[0].default", "default"},
        {"[[parameter]]\nname = \"K\"\nmin = 1\nmax = 0\ndefault = 0.5\n[profile]\n" + good_rd, 4,
         "parameter[0].max", "max is below min"},
        {"[[parameter]]\nname = \"eta\"\nmin = 1\nmax = 2\ndefault = 1.5\n[profile]\n" + good_rd, 2,
         "parameter[0].name", "'eta' is taken"},
        {"[[parameter]]\nname = \"2k\"\nmin = 1\nmax = 2\ndefault = 1.5\n[profile]\n" + good_rd, 2,
         "parameter[0].name", "not an identifier"},
        {"[profile\n" + good_rd, 1, "", ""},
    };
    for (const Case& c : cases) {
        const InputError e = error_of(c.text);
        EXPECT_EQ(e.where().file, "bad.toml");
        EXPECT_EQ(e.where().line, c.line) << c.text << "\n" << e.what();
        EXPECT_NE(e.key().find(c.key), std::string::npos)
            << "key '" << e.key() << "', expected " << c.key << "\n"
            << e.what();
        EXPECT_NE(std::string(e.what()).find(c.says), std::string::npos)
            << "expected '" << c.says << "' in: " << e.what();
    }
}
