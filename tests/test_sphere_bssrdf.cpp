// Analytic profiles integrated over the lit sphere (approx/sphere_bssrdf.h) against closed forms
// and an independent quadrature, and `ssslab sphere` end to end. Expected values come from this
// file: the transmitted power of a constant profile (volpath's disc average of the Fresnel
// reflectance, a separate quadrature), the delta limit, the half-space limit of a large sphere,
// a brute-force tensor quadrature over the sphere in graded polar coordinates, bounds on the
// unlit pole, and volpath's own camera.
#include "approx/diffusion.h"
#include "approx/sphere_bssrdf.h"
#include "core/film_image.h"
#include "core/quadrature.h"
#include "testing.h"
#include "volpath/sampling.h"
#include "volpath/sphere.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace ssslab::approx {
namespace {

namespace fs = std::filesystem;
constexpr double kPi = 3.14159265358979323846;

double deg(double d) {
    return d * kPi / 180.0;
}

// E_t / E0 with volpath's Fresnel (an implementation independent of approx's).
double entry(double mu, double eta, bool fresnel) {
    if (mu <= 0) return 0;
    return fresnel ? mu * (1 - volpath::fresnel_dielectric(mu, eta)) : mu;
}

// M(beta) by brute force: psi = pi t^3 (graded towards the exit point) in composite
// Gauss-Legendre panels split at the terminator tangencies, phi split where the entry cosine
// crosses 0; dA = R^2 sin psi dpsi dphi, chord 2 R sin(psi / 2).
double brute_force(const RadialFunction& rd, double radius, double beta, double eta, bool fresnel) {
    std::vector<double> x, w;
    gauss_legendre(16, x, w);
    std::vector<double> tb = {0.0, 1.0};
    for (double psi : {std::abs(0.5 * kPi - beta), 0.5 * kPi + beta})
        if (psi > 0 && psi < kPi) tb.push_back(std::cbrt(psi / kPi));
    std::sort(tb.begin(), tb.end());
    const int panels = 300;
    double total = 0;
    for (size_t s = 0; s + 1 < tb.size(); ++s) {
        const double ta = tb[s], tbb = tb[s + 1];
        const int np = std::max(4, static_cast<int>(panels * (tbb - ta)));
        for (int p = 0; p < np; ++p) {
            const double a = ta + (tbb - ta) * p / np, b = ta + (tbb - ta) * (p + 1) / np;
            for (size_t i = 0; i < x.size(); ++i) {
                const double t = 0.5 * (a + b) + 0.5 * (b - a) * x[i];
                const double psi = kPi * t * t * t, dpsi = 3 * kPi * t * t * 0.5 * (b - a) * w[i];
                const double ca = std::cos(psi) * std::cos(beta),
                             cb = std::sin(psi) * std::sin(beta);
                // phi in [0, pi] (symmetric), lit for phi < phi0.
                double phi0 = kPi;
                if (ca - cb < 0)
                    phi0 = ca + cb <= 0 ? 0.0 : std::acos(std::clamp(-ca / cb, -1.0, 1.0));
                double g = 0;
                for (size_t j = 0; j < x.size(); ++j)
                    for (int half = 0; half < 4; ++half) {  // 4 sub-panels of [0, phi0]
                        const double lo = phi0 * half / 4, hi = phi0 * (half + 1) / 4;
                        const double phi = 0.5 * (lo + hi) + 0.5 * (hi - lo) * x[j];
                        g += 0.5 * (hi - lo) * w[j] * entry(ca + cb * std::cos(phi), eta, fresnel);
                    }
                g *= 2;  // both halves of the circle
                total += radius * radius * std::sin(psi) * rd(2 * radius * std::sin(0.5 * psi)) *
                         g * dpsi;
            }
        }
    }
    return total;
}

DiffusionMedium skin1_red() {
    DiffusionMedium m;  // Skin1, red channel, per cm
    m.sigma_a = 0.32;
    m.sigma_s = 7.4;
    m.g = 0;
    m.eta = 1.3;
    return m;
}

// ---- Closed forms -----------------------------------------------------------------------------

TEST(SphereBssrdf, ConstantProfileGivesTheTransmittedPower) {
    const double c = 0.7, R = 2.0;
    const RadialFunction flat = [c](double) { return c; };
    SphereIntegration o;
    o.radius = R;
    o.beta_bins = 18;
    // eta = 1: T = 1 for both entry weights, M = c pi R^2 E0 at every beta.
    for (EntryWeight e : {EntryWeight::kFresnel, EntryWeight::kCosineOnly}) {
        o.eta = 1.0;
        o.entry = e;
        const SphereExitance t = integrate_sphere(flat, o);
        for (double v : t.node_value) EXPECT_NEAR(v / (c * kPi * R * R), 1.0, 1e-9);
        for (double v : t.bin_mean) EXPECT_NEAR(v / (c * kPi * R * R), 1.0, 1e-9);
        EXPECT_NEAR(t.total_fraction() / (4 * kPi * R * R * c), 1.0, 1e-9);
    }
    // Fresnel entry: c times the power transmitted by the sphere, pi R^2 (1 - rho(eta)), rho the
    // disc average of F (volpath's quadrature); eta < 1 has a critical angle. A profile that
    // carries the normal-incidence factor is divided by 1 - F(1).
    o.entry = EntryWeight::kFresnel;
    for (double eta : {1.3, 1.5, 0.75}) {
        o.eta = eta;
        const double transmitted = 1 - volpath::sphere_specular_reflectance(eta);
        o.profile_entry_fresnel = false;
        const SphereExitance t = integrate_sphere(flat, o);
        for (double v : t.node_value)
            EXPECT_NEAR(v / (c * kPi * R * R * transmitted), 1.0, 1e-9) << "eta " << eta;
        o.profile_entry_fresnel = true;
        const double f1 = volpath::fresnel_dielectric(1.0, eta);
        const double v = sphere_exitance_at(flat, deg(70), o);
        EXPECT_NEAR(v * (1 - f1) / (c * kPi * R * R * transmitted), 1.0, 1e-9) << "eta " << eta;
    }
}

TEST(SphereBssrdf, NarrowProfileReturnsTheTransmittedIrradiance) {
    // A unit-integral Gaussian of width 1e-4 R: M(beta) -> E_t(beta) = max(0, cos beta) T.
    const double R = 1.0, w = 1e-4 * R;
    const RadialFunction gauss = [w](double r) {
        return std::exp(-r * r / (2 * w * w)) / (2 * kPi * w * w);
    };
    SphereIntegration o;
    o.radius = R;
    o.eta = 1.3;
    for (double b : {0.0, 30.0, 60.0, 85.0, 89.0, 90.0, 91.0, 120.0, 180.0}) {
        const double expected = entry(std::cos(deg(b)), 1.3, true);
        EXPECT_NEAR(sphere_exitance_at(gauss, deg(b), o), expected, 1e-4) << b << " deg";
    }
    // Bin means with the cosine entry: the zone average of max(0, cos beta) is
    // (cos b0 + cos b1) / 2 on the lit side (the terminator is a bin edge) and 0 beyond.
    o.entry = EntryWeight::kCosineOnly;
    o.beta_bins = 36;
    const SphereExitance t = integrate_sphere(gauss, o);
    for (int j = 0; j < o.beta_bins; ++j) {
        const double b0 = t.beta_edge(j), b1 = t.beta_edge(j + 1);
        const double expected = b1 <= 0.5 * kPi + 1e-12 ? 0.5 * (std::cos(b0) + std::cos(b1)) : 0.0;
        EXPECT_NEAR(t.bin_mean[static_cast<size_t>(j)], expected, 1e-4) << "bin " << j;
    }
}

TEST(SphereBssrdf, LargeSphereApproachesTheHalfSpace) {
    // R = 1000 cm against a diffuse mean free path of ~0.6 cm: M at the subsolar point is the
    // half-space's total diffuse reflectance times the entry weight at normal incidence.
    DiffusionMedium m;
    m.sigma_a = 0.1;
    m.sigma_s = 10;
    m.eta = 1.3;
    const auto dipole = make_diffusion_profile("dipole", m);
    SphereIntegration o;
    o.radius = 1000;
    o.eta = 1.3;
    const double t1 = 1 - volpath::fresnel_dielectric(1.0, 1.3);
    const RadialFunction rd = [&](double r) { return dipole->rd(r); };
    EXPECT_NEAR(sphere_exitance_at(rd, 0.0, o) / (dipole->total_rd() * t1), 1.0, 1e-3);
    o.entry = EntryWeight::kCosineOnly;
    EXPECT_NEAR(sphere_exitance_at(rd, 0.0, o) / dipole->total_rd(), 1.0, 1e-3);
    // At 60 deg, the irradiance is halved (curvature corrections O(l_d / R)).
    EXPECT_NEAR(sphere_exitance_at(rd, deg(60), o) / (0.5 * dipole->total_rd()), 1.0, 1e-3);
}

// ---- Against an independent quadrature, and convergence -----------------------------------------

TEST(SphereBssrdf, AgreesWithBruteForceQuadrature) {
    const auto dipole = make_diffusion_profile("dipole", skin1_red());
    const RadialFunction rd = [&](double r) { return dipole->rd(r); };
    for (bool fresnel : {true, false}) {
        SphereIntegration o;
        o.radius = 0.5;
        o.eta = 1.3;
        o.entry = fresnel ? EntryWeight::kFresnel : EntryWeight::kCosineOnly;
        for (double b : {0.0, 60.0, 100.0, 180.0}) {
            const double ref = brute_force(rd, 0.5, deg(b), 1.3, fresnel);
            EXPECT_NEAR(sphere_exitance_at(rd, deg(b), o) / ref, 1.0, 1e-6)
                << b << " deg, fresnel " << fresnel;
        }
    }
}

TEST(SphereBssrdf, ConvergesUnderRefinement) {
    // Every model of the default comparison, on the sphere of `ssslab sphere`'s default set-up
    // (Skin1, R = 5 mm, red: the widest profile), and a small sphere of blue.
    for (const char* name : {"dipole", "better-dipole", "pbd"}) {
        for (double radius : {0.5, 0.1}) {
            DiffusionMedium m = skin1_red();
            if (radius < 0.5) m.sigma_a = 4.8, m.sigma_s = 10.1;
            const auto p = make_diffusion_profile(name, m);
            SphereIntegration o;
            o.radius = radius;
            o.eta = m.eta;  // integrate_sphere(profile) takes it from the profile
            o.beta_bins = 60;
            const SphereExitance base = integrate_sphere(*p, o);
            EXPECT_LT(base.max_rel_error, 1e-9) << name;
            EXPECT_LT(base.fit_error, 1e-10) << name;
            SphereIntegration fine = o;
            fine.rel_tol = 1e-13;
            fine.nodes_per_bin = 8;
            const SphereExitance ref = integrate_sphere(*p, fine);
            for (size_t j = 0; j < base.bin_mean.size(); ++j)
                EXPECT_NEAR(base.bin_mean[j] / ref.bin_mean[j], 1.0, 1e-6)
                    << name << " R " << radius << " bin " << j;
        }
    }
}

TEST(SphereBssrdf, InterpolatesBetweenNodes) {
    // SphereExitance::at (what the images use) against direct integration, with the 180 bins of
    // `ssslab sphere` (nodes ~0.25 deg apart).
    for (const char* name : {"dipole", "pbd"}) {
        for (double radius : {0.5, 0.1}) {
            DiffusionMedium m = skin1_red();
            if (radius < 0.5) m.sigma_a = 4.8, m.sigma_s = 10.1;
            const auto p = make_diffusion_profile(name, m);
            SphereIntegration o;
            o.radius = radius;
            o.eta = m.eta;
            const SphereExitance t = integrate_sphere(*p, o);
            for (double b : {0.3, 44.9, 89.6, 90.2, 135.7, 179.8}) {
                const double direct =
                    sphere_exitance_at([&](double r) { return p->rd(r); }, deg(b), o);
                EXPECT_NEAR(t.at(deg(b)) / direct, 1.0, 1e-5) << name << " " << b << " deg";
            }
        }
    }
}

TEST(SphereBssrdf, UnlitPoleGetsOnlyTheTail) {
    // Cosine entry, a monotone profile: the lit hemisphere lies at chords in [sqrt(2) R, 2 R]
    // from the antipode and transmits pi R^2 E0, so pi R^2 R_d(2R) <= M(pi) <= pi R^2
    // R_d(sqrt(2) R).
    const auto dipole = make_diffusion_profile("dipole", skin1_red());
    SphereIntegration o;
    o.radius = 0.5;
    o.entry = EntryWeight::kCosineOnly;
    o.beta_bins = 18;
    const SphereExitance t = integrate_sphere(*dipole, o);
    const double m = t.node_value.back(), R = o.radius;
    EXPECT_TRUE(std::isfinite(m));
    EXPECT_GT(m, kPi * R * R * dipole->rd(2 * R));
    EXPECT_LT(m, kPi * R * R * dipole->rd(std::sqrt(2.0) * R));
    // M decreases from the subsolar point to the antipode, and every value is positive.
    for (size_t i = 0; i + 1 < t.node_value.size(); ++i) {
        EXPECT_GT(t.node_value[i], t.node_value[i + 1]) << i;
        EXPECT_GT(t.node_value[i + 1], 0.0);
    }
}

// ---- Images -------------------------------------------------------------------------------------

TEST(SphereBssrdf, ViewMatchesVolpathCamera) {
    struct Case {
        std::array<double, 3> v, up;
        int w, h;
        double s;
    };
    const Case cases[] = {{{0, 0, 1}, {0, 0, 0}, 32, 32, 1.1},
                          {{0.3, 0.95, 0.1}, {0, 0, 0}, 40, 24, 1.3},
                          {{1, -2, 0.5}, {0.2, 0.1, 1}, 17, 33, 1.0},
                          {{0.5, 0, 0.8660254037844386}, {0, 0, 0}, 8, 8, 1.1}};
    for (const Case& c : cases) {
        volpath::SphereScene sc;
        sc.radius_cm = 2.5;
        sc.to_camera = {c.v[0], c.v[1], c.v[2]};
        sc.up = {c.up[0], c.up[1], c.up[2]};
        sc.width = c.w;
        sc.height = c.h;
        sc.frame_scale = c.s;
        const volpath::SphereCamera cam = volpath::sphere_camera(sc);
        SphereView v;
        v.to_camera = c.v;
        v.up = c.up;
        v.width = c.w;
        v.height = c.h;
        v.frame_scale = c.s;
        const SphereViewFrame f = resolve_view(v);
        const double R = sc.radius_cm;
        EXPECT_NEAR(f.pixel * R, cam.pixel_cm, 1e-14);
        EXPECT_NEAR(f.half_x * R, cam.half_x, 1e-13);
        EXPECT_NEAR(f.half_y * R, cam.half_y, 1e-13);
        for (int k = 0; k < 3; ++k) {
            const double vr[3] = {cam.right.x, cam.right.y, cam.right.z};
            const double vu[3] = {cam.up.x, cam.up.y, cam.up.z};
            EXPECT_NEAR(f.right[static_cast<size_t>(k)], vr[k], 1e-15);
            EXPECT_NEAR(f.up[static_cast<size_t>(k)], vu[k], 1e-15);
        }
    }
    SphereView bad;
    bad.up = {0, 0, 2};  // parallel to to_camera
    EXPECT_THROW(resolve_view(bad), std::invalid_argument);
}

TEST(SphereBssrdf, ImageIsSymmetricAndMatchesTheTable) {
    const auto dipole = make_diffusion_profile("dipole", skin1_red());
    SphereIntegration o;
    o.radius = 0.5;
    const SphereExitance t = integrate_sphere(*dipole, o);
    SphereView v;  // light and camera along +z: the image is invariant under the square's group
    v.width = v.height = 24;
    const std::vector<double> img = sphere_exitance_image(t, v);
    const int n = v.width;
    auto at = [&](int x, int y) { return img[static_cast<size_t>(y * n + x)]; };
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            EXPECT_NEAR(at(x, y), at(n - 1 - x, y), 1e-12 * at(x, y) + 1e-300);
            EXPECT_NEAR(at(x, y), at(x, n - 1 - y), 1e-12 * at(x, y) + 1e-300);
            EXPECT_NEAR(at(x, y), at(y, x), 1e-12 * at(x, y) + 1e-300);
        }
    EXPECT_EQ(at(0, 0), 0.0);  // the corner is off the disc (frame 1.1 R)
    // Near the centre the pixel average is M(beta) / pi at the pixel's centre to second order.
    const SphereViewFrame f = resolve_view(v);
    const auto p = f.image_point(n / 2, n / 2);
    const double beta = std::asin(std::hypot(p[0], p[1]));
    EXPECT_NEAR(at(n / 2, n / 2) / (t.at(beta) / kPi), 1.0, 1e-3);
}

// ---- Bad input ----------------------------------------------------------------------------------

TEST(SphereBssrdf, RejectsBadOptions) {
    const RadialFunction flat = [](double) { return 1.0; };
    SphereIntegration o;
    o.radius = -1;
    EXPECT_THROW(integrate_sphere(flat, o), std::invalid_argument);
    o.radius = 1;
    o.nodes_per_bin = 0;
    EXPECT_THROW(integrate_sphere(flat, o), std::invalid_argument);
    o.nodes_per_bin = 4;
    EXPECT_THROW(sphere_exitance_at(flat, 4.0, o), std::invalid_argument);
    const RadialFunction singular = [](double r) { return r < 1e-3 ? INFINITY : 1.0; };
    EXPECT_THROW(sphere_exitance_at(singular, 0.0, o), std::invalid_argument);
}

// ---- The command line ---------------------------------------------------------------------------

std::vector<std::string> csv_header(const fs::path& p) {
    std::ifstream in(p);
    std::string line;
    std::getline(in, line);
    std::vector<std::string> cols;
    std::stringstream ss(line);
    for (std::string c; std::getline(ss, c, ',');) cols.push_back(c);
    return cols;
}

int csv_rows(const fs::path& p) {
    std::ifstream in(p);
    int n = 0;
    for (std::string line; std::getline(in, line);) ++n;
    return n - 1;
}

TEST(SphereCli, WritesImagesProfilesAndRecord) {
    testing::TempDir dir;
    dir.write("s.toml",
              "models = [\"dipole\", \"better-dipole\"]\n"
              "[material]\npreset = \"Skin1\"\n"
              "[sphere]\nradius_mm = 5\nsize = 16\nbeta_bins = 36\n"
              "[budget]\nphotons = 20000\n");
    const auto r =
        testing::run_ssslab({"sphere", "--config", "s.toml", "--out", "out/s"}, dir.path());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    for (const char* f : {"s.exr", "s.png", "s_beta.csv", "s.toml"})
        EXPECT_TRUE(fs::exists(dir / "out" / f)) << f;
    std::vector<std::string> files;
    for (const auto& e : fs::directory_iterator(dir / "out"))
        files.push_back(e.path().filename().string());
    std::sort(files.begin(), files.end());
    EXPECT_EQ(files, (std::vector<std::string>{"s.exr", "s.png", "s.toml", "s_beta.csv"}));

    const LayeredImage img = read_exr((dir / "out" / "s.exr").string());
    EXPECT_EQ(img.width(), 16);
    for (const char* l :
         {"exitance", "exitance.stderr", "subsurface", "subsurface.stderr", "specular",
          "specular.stderr", "radiance", "radiance.stderr", "model.dipole", "model.better-dipole"})
        EXPECT_TRUE(img.has_layer(l)) << l;
    // The model image is positive on the sphere and 0 in the corner.
    EXPECT_GT(img.layer("model.dipole").at(8, 8, 0), 0.0f);
    EXPECT_EQ(img.layer("model.dipole").at(0, 0, 0), 0.0f);

    const auto cols = csv_header(dir / "out" / "s_beta.csv");
    for (const char* c : {"beta_lo_deg", "beta_hi_deg", "M_volpath_R", "M_volpath_se_R",
                          "M_volpath_single_G", "M_volpath_single_se_B", "M_dipole_R", "z_dipole_R",
                          "M_better-dipole_B", "z_better-dipole_B"})
        EXPECT_NE(std::find(cols.begin(), cols.end(), c), cols.end()) << c;
    EXPECT_EQ(cols.size(), 2u + 3u * (4u + 2u * 2u));
    EXPECT_EQ(csv_rows(dir / "out" / "s_beta.csv"), 36);

    const std::string rec = testing::read_text(dir / "out" / "s.toml");
    for (const char* key :
         {"preset = 'Skin1'", "radius_mm = 5", "[result_R]", "dipole_chi2",
          "diffuse_single_fraction", "dipole_compared_with = 'volpath_multiple_scattering'",
          "dipole_rel_l2_lit", "[timing]", "[provenance]", "git_revision"})
        EXPECT_NE(rec.find(key), std::string::npos) << key << " in\n" << rec;
    for (const char* s : {"relL2 lit", "better-dipole", "chi2/dof"})
        EXPECT_NE(r.out.find(s), std::string::npos) << s << " in\n" << r.out;
}

TEST(SphereCli, BadInputExitsTwoNamingTheKeyWithoutOutput) {
    testing::TempDir dir;
    struct Case {
        std::vector<std::string> args;
        std::string key;
    };
    const std::vector<Case> cases = {
        {{"--material", "Skn1"}, "--material"},
        {{"--material", "Skin1", "--radius-mm", "-1"}, "--radius-mm"},
        {{"--material", "Skin1", "--models", "dipole,bogus"}, "--models"},
        {{"--material", "Skin1", "--mode", "weighted"}, "--mode"},
        {{"--config", "bad.toml"}, "bad.toml:5"},
        {{"--config", "bad2.toml"}, "sphere.frame"},
    };
    dir.write("bad.toml", "[material]\npreset = \"Skin1\"\n\n[sphere]\nradius_mm = -2\n");
    dir.write("bad2.toml", "[material]\npreset = \"Skin1\"\n[sphere]\nframe = 2\n");
    for (const Case& c : cases) {
        std::vector<std::string> args = {"sphere"};
        args.insert(args.end(), c.args.begin(), c.args.end());
        args.insert(args.end(), {"--photons", "1000", "--out", "o/x"});
        const auto r = testing::run_ssslab(args, dir.path());
        EXPECT_EQ(r.exit_code, 2) << c.key << ": " << r.err;
        EXPECT_NE(r.err.find(c.key), std::string::npos) << r.err;
        EXPECT_FALSE(fs::exists(dir / "o")) << c.key;
    }
}

}  // namespace
}  // namespace ssslab::approx
