// Kernel2D and the models of Freude14 ch. 5 against linear algebra and independent solvers.
#include "approx/kernel2d.h"
#include "approx/model_spec.h"
#include "approx/models.h"
#include "core/profile.h"

#include <gtest/gtest.h>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

namespace ssslab::approx {
namespace {

// A diffusion-like radial profile, exp(-r/l)/r terms, in MCML's layout (annulus bins in cm).
RadialProfile analytic_profile(int nr, double dr_cm, double near_cm, double far_cm) {
    RadialProfile p;
    p.name = "analytic";
    p.dr_cm = dr_cm;
    p.nr = nr;
    for (int c = 0; c < 3; ++c) {
        const double s = 1.0 + 0.5 * c;  // channels differ in width
        p.rd_per_cm2[c].resize(static_cast<size_t>(nr));
        p.se_per_cm2[c].assign(static_cast<size_t>(nr), 0.0);
        for (int i = 0; i < nr; ++i) {
            const double r = (i + 0.5) * dr_cm;
            p.rd_per_cm2[c][static_cast<size_t>(i)] =
                0.6 * std::exp(-r / (near_cm / s)) / r + 0.4 * std::exp(-r / (far_cm / s)) / r;
        }
    }
    return p;
}

TEST(Kernel2D, SymmetricNormalisedAndHoldsTheProfilesMass) {
    const RadialProfile p = analytic_profile(60, 0.01, 0.02, 0.1);
    const Kernel2D k(p, 0, KernelGrid::from_profile(p));
    EXPECT_EQ(k.n(), 60);
    EXPECT_NEAR(k.h_mm(), 0.1, 1e-15);
    EXPECT_NEAR(4.0 * k.quadrant().sum(), 1.0, 1e-13);
    EXPECT_LT((k.quadrant() - k.quadrant().transpose()).cwiseAbs().maxCoeff(), 1e-18);
    EXPECT_EQ(k.at(-1, 0), k.at(0, 0));  // cell -1 mirrors cell 0
    EXPECT_EQ(k.at(3, -5), k.at(3, 4));
    // The grid is a square holding the disk of radius n h and a little more: its raw mass lies
    // between the profile's mass inside the disk and its whole mass (in 1/mm^2 x mm^2).
    double disk = 0;
    for (int i = 0; i < p.nr; ++i)
        disk += p.rd_per_cm2[0][static_cast<size_t>(i)] * M_PI * (2 * i + 1) * p.dr_cm * p.dr_cm;
    EXPECT_NEAR(k.raw_l1(), disk, 0.01 * disk);
    EXPECT_LE(k.raw_l1(), disk * (1 + 1e-9) + 1e-12);
}

TEST(Kernel2D, EmptyChannelIsAnError) {
    RadialProfile p = analytic_profile(10, 0.01, 0.02, 0.1);
    std::fill(p.rd_per_cm2[1].begin(), p.rd_per_cm2[1].end(), 0.0);
    EXPECT_THROW(Kernel2D(p, 1, KernelGrid::from_profile(p)), std::invalid_argument);
}

// The full 2n x 2n symmetric matrix's eigen-decomposition, truncated to its N largest
// magnitudes: the reference for the Lanczos path on the even block.
Eigen::MatrixXd truncated_full(const Kernel2D& k, int rank, std::vector<double>& sigma) {
    const Eigen::MatrixXd f = k.full();
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(f);
    std::vector<int> idx(static_cast<size_t>(f.rows()));
    for (int i = 0; i < f.rows(); ++i) idx[static_cast<size_t>(i)] = i;
    std::sort(idx.begin(), idx.end(), [&](int a, int b) {
        return std::fabs(es.eigenvalues()(a)) > std::fabs(es.eigenvalues()(b));
    });
    Eigen::MatrixXd a = Eigen::MatrixXd::Zero(f.rows(), f.cols());
    sigma.clear();
    for (int r = 0; r < rank; ++r) {
        const int i = idx[static_cast<size_t>(r)];
        a += es.eigenvalues()(i) * es.eigenvectors().col(i) * es.eigenvectors().col(i).transpose();
        sigma.push_back(std::fabs(es.eigenvalues()(i)));
    }
    return a;
}

TEST(Svd, RankNEqualsTheTruncatedFullDecomposition) {
    // n = 300 > 256 takes the Lanczos (Spectra) path; n = 40 the dense path.
    for (int nr : {40, 300}) {
        const RadialProfile p = analytic_profile(nr, 0.002, 0.01, 0.08);
        const Kernel2D k(p, 1, KernelGrid::from_profile(p));
        for (int rank : {1, 2, 3, 6}) {
            SCOPED_TRACE("n = " + std::to_string(nr) + ", rank " + std::to_string(rank));
            std::vector<double> sigma;
            const Eigen::MatrixXd ref = truncated_full(k, rank, sigma);
            const ModelResult m = svd_rank_n(k, rank, false);
            double maxdiff = 0;
            for (int x = -k.n(); x < k.n(); ++x)
                for (int y = -k.n(); y < k.n(); ++y)
                    maxdiff =
                        std::max(maxdiff, std::fabs(m.kernel.at(x, y) - ref(x + k.n(), y + k.n())));
            EXPECT_LT(maxdiff, 1e-12 * k.quadrant().maxCoeff() * 1e3);
            for (int r = 0; r < rank; ++r)
                EXPECT_NEAR(m.info.at("sigma_" + std::to_string(r + 1)),
                            sigma[static_cast<size_t>(r)], 1e-10 * sigma[0]);
            // Eq. 5.12: the renormalised variant has unit L1 and is a multiple of the plain one.
            const ModelResult l1 = svd_rank_n(k, rank, true);
            EXPECT_NEAR(l1.kernel.l1(), 1.0, 1e-12);
            EXPECT_NEAR(l1.kernel.at(0, 0) / m.kernel.at(0, 0), 1.0 / m.info.at("l1"), 1e-9);
        }
        const std::vector<double> s30 = singular_values(k, 30);
        std::vector<double> sigma;
        truncated_full(k, 30, sigma);
        for (int r = 0; r < 30; ++r)
            EXPECT_NEAR(s30[static_cast<size_t>(r)], sigma[static_cast<size_t>(r)],
                        1e-10 * sigma[0]);
    }
}

TEST(Svd, RankOneHasTheLowestKernelSpaceRmsOfAllRankOneModels) {
    // Eckart-Young: no rank-1 kernel is closer to K in the Frobenius norm than the SVD's.
    const RadialProfile p = analytic_profile(120, 0.005, 0.015, 0.12);
    for (int c = 0; c < 3; ++c) {
        const Kernel2D k(p, c, KernelGrid::from_profile(p));
        const double svd = kernel_errors(k, svd_rank_n(k, 1, false).kernel).rms;
        EXPECT_LT(svd, kernel_errors(k, svd_rank_n(k, 1, true).kernel).rms);
        EXPECT_LT(svd, kernel_errors(k, preintegration(k).kernel).rms);
        for (GuideParams g :
             {GuideParams{0, 0}, GuideParams{1, 0}, GuideParams{2, 0}, GuideParams{1.55, 50}})
            EXPECT_LT(svd, kernel_errors(k, guided(k, g).kernel).rms) << g.k << " " << g.b;
    }
}

TEST(Preintegration, RowSumsWithExactEnergy) {
    const RadialProfile p = analytic_profile(80, 0.005, 0.015, 0.1);
    const Kernel2D k(p, 2, KernelGrid::from_profile(p));
    const ModelResult m = preintegration(k);
    ASSERT_EQ(m.kernel.rank(), 1);
    EXPECT_NEAR(m.kernel.sum(), 1.0, 1e-13);
    EXPECT_NEAR(m.kernel.l1(), 1.0, 1e-13);
    // a_p(x) = sum over y of K(x, y) (Eq. 5.17 with ||K||_1 = 1).
    for (int x : {0, 5, 40, 79}) {
        double row = 0;
        for (int y = -k.n(); y < k.n(); ++y) row += k.at(x, y);
        EXPECT_NEAR(m.kernel.terms[0].a[static_cast<size_t>(x)], row, 1e-15);
    }
}

// An independent solver of the k = 0, b = 0 problem: Newton's method on the KKT system of
// min ||K - a a^T||_F^2 subject to sum a = 1 (a > 0 at the optimum), on the full grid with the
// dense Hessian. Different algorithm, different parametrisation (full, not the even half).
Eigen::VectorXd newton_kkt(const Eigen::MatrixXd& K, Eigen::VectorXd a) {
    const Eigen::Index m = K.rows();
    double mu = 0;
    for (int it = 0; it < 100; ++it) {
        const double aa = a.squaredNorm();
        const Eigen::VectorXd g = -4.0 * K * a + 4.0 * aa * a;  // gradient of f
        Eigen::MatrixXd H = -4.0 * K + 8.0 * a * a.transpose();
        H.diagonal().array() += 4.0 * aa;
        Eigen::MatrixXd J = Eigen::MatrixXd::Zero(m + 1, m + 1);
        J.topLeftCorner(m, m) = H;
        J.topRightCorner(m, 1).setOnes();
        J.bottomLeftCorner(1, m).setOnes();
        Eigen::VectorXd rhs(m + 1);
        rhs.head(m) = -(g + mu * Eigen::VectorXd::Ones(m));
        rhs(m) = -(a.sum() - 1.0);
        const Eigen::VectorXd d = J.fullPivLu().solve(rhs);
        a += d.head(m);
        mu += d(m);
        if (d.head(m).norm() < 1e-15) break;
    }
    return a;
}

TEST(Guided, ConstraintHeldAndKZeroOptimumMatchesAnIndependentSolver) {
    const RadialProfile p = analytic_profile(12, 0.01, 0.02, 0.15);
    const Kernel2D k(p, 0, KernelGrid::from_profile(p));
    const ModelResult m = guided(k, {0, 0});
    EXPECT_LT(m.info.at("constraint_error"), 1e-6);
    // Newton from the pre-integrated kernel (full grid, sum 1).
    const Eigen::MatrixXd K = k.full();
    Eigen::VectorXd a0(K.rows());
    for (int x = 0; x < K.rows(); ++x) a0(x) = K.row(x).sum();
    const Eigen::VectorXd a = newton_kkt(K, a0);
    ASSERT_GT(a.minCoeff(), 0.0) << "the optimum is interior here";
    for (int x = -k.n(); x < k.n(); ++x)
        EXPECT_NEAR(m.kernel.terms[0].a[static_cast<size_t>(Kernel2D::fold(x))], a(x + k.n()),
                    1e-9 * a.maxCoeff())
            << "x = " << x;
}

TEST(Guided, EveryGuideHoldsTheConstraintOnRealisticKernels) {
    const RadialProfile p = analytic_profile(400, 0.002, 0.01, 0.1);
    for (GuideParams g : {GuideParams{0, 0}, GuideParams{1, 0}, GuideParams{2, 0},
                          GuideParams{4, 0}, GuideParams{1.55, 50}, GuideParams{0, 50}}) {
        const Kernel2D k(p, 1, KernelGrid::from_profile(p));
        const ModelResult m = guided(k, g);
        SCOPED_TRACE("k = " + std::to_string(g.k) + " b = " + std::to_string(g.b));
        EXPECT_LT(m.info.at("constraint_error"), 1e-6);
        EXPECT_LT(m.info.at("last_change"), 1e-11);
        for (double v : m.kernel.terms[0].a) ASSERT_TRUE(std::isfinite(v) && v >= 0);
    }
    EXPECT_THROW(guided(Kernel2D(p, 0, KernelGrid::from_profile(p)), {5, 0}),
                 std::invalid_argument);
}

TEST(Guided, LargeGridsSolvedOnTwoLevelsMeetTheKktConditions) {
    // n >= 512 takes the two-level path (a coarse solve as the start). Whatever the path, the
    // result must be a KKT point of min sum Gamma (K - a a^T)^2, sum a = 1/2 (half vector), a >= 0:
    // g_i = B_i - a_i D_i with B = (Gamma o K) a, D = Gamma (a o a) is one constant mu where
    // a_i > 0 and at most mu where a_i = 0. Gamma is evaluated here from Eq. 5.20 independently.
    const RadialProfile p = analytic_profile(600, 0.001, 0.004, 0.05);
    for (GuideParams g : {GuideParams{1, 0}, GuideParams{1.55, 50}}) {
        SCOPED_TRACE("k = " + std::to_string(g.k) + " b = " + std::to_string(g.b));
        const Kernel2D k(p, 2, KernelGrid::from_profile(p));
        ASSERT_GE(k.n(), 512);
        const ModelResult m = guided(k, g);
        EXPECT_LT(m.info.at("constraint_error"), 1e-6);
        const std::vector<double>& a = m.kernel.terms[0].a;
        const int n = k.n();
        std::vector<double> grad(static_cast<size_t>(n));
        double mu = 0, scale = 0;
        int active = 0;
        for (int i = 0; i < n; ++i) {
            double B = 0, D = 0;
            for (int j = 0; j < n; ++j) {
                const double x = (i + 0.5) / n, y = (j + 0.5) / n;
                const double gamma =
                    std::pow(x * x + y * y, 0.5 * g.k) *
                    (g.b > 0 ? (1 - std::exp(-g.b * x * x)) * (1 - std::exp(-g.b * y * y)) : 1.0);
                B += gamma * k.quadrant()(i, j) * a[static_cast<size_t>(j)];
                D += gamma * a[static_cast<size_t>(j)] * a[static_cast<size_t>(j)];
            }
            grad[static_cast<size_t>(i)] = B - a[static_cast<size_t>(i)] * D;
            scale = std::max(scale, std::fabs(B));
            if (a[static_cast<size_t>(i)] > 0) mu += grad[static_cast<size_t>(i)], ++active;
        }
        ASSERT_GT(active, 0);
        mu /= active;
        double worst = 0;
        for (int i = 0; i < n; ++i) {
            const double gi = grad[static_cast<size_t>(i)];
            worst = std::max(
                worst, a[static_cast<size_t>(i)] > 0 ? std::fabs(gi - mu) : std::max(0.0, gi - mu));
        }
        std::printf("n = %d, %d of %d cells active, KKT residual %.2e of max B, %g iterations\n", n,
                    active, n, worst / scale, m.info.at("iterations"));
        EXPECT_LT(worst, 1e-8 * scale);
    }
}

TEST(Guided, LargerKApproximatesTheFalloffMoreClosely) {
    // [Freude14 §5.3]: with larger k the outer regions (falloff) are approximated more closely,
    // at the expense of the centre.
    const RadialProfile p = analytic_profile(200, 0.003, 0.01, 0.12);
    const Kernel2D k(p, 0, KernelGrid::from_profile(p));
    const ModelResult g0 = guided(k, {0, 0}), g2 = guided(k, {2, 0});
    const int split = k.n() / 8;
    auto errors = [&](const SeparableKernel& a, double& centre, double& falloff) {
        centre = falloff = 0;
        for (int i = 0; i < k.n(); ++i)
            for (int j = 0; j < k.n(); ++j) {
                const double d = a.at(i, j) - k.at(i, j);
                (i * i + j * j < split * split ? centre : falloff) += d * d;
            }
    };
    double c0, f0, c2, f2;
    errors(g0.kernel, c0, f0);
    errors(g2.kernel, c2, f2);
    EXPECT_LT(f2, f0);
    EXPECT_GT(c2, c0);
}

// ---- The name -> factory table (approx/model_spec.h) -------------------------------------------

// A model registered as a program outside ssslab would: the pre-integrated kernel scaled by a
// factor, so what it builds is known from the built-in model.
void register_scaled_preintegration() {
    static bool done = false;
    if (done) return;
    done = true;
    ModelFactory f;
    f.name = "test_scaled";
    f.keys = {"f"};
    f.help = "test_scaled:f=F (a test's model)";
    f.version = "test-scaled-1";
    f.validate = [](const ModelSpec& m) {
        if (!(m.number("f", 1) > 0)) throw std::invalid_argument("model \"" + m.text + "\": f > 0");
    };
    f.build = [](const ModelSpec& m, const Kernel2D& k, const ModelContext&) {
        ModelResult r = preintegration(k);
        r.kernel.scale(m.number("f", 1));
        return r;
    };
    register_model(std::move(f));
}

TEST(ModelRegistry, ARegisteredModelIsParsedValidatedAndBuiltLikeTheBuiltIns) {
    register_scaled_preintegration();
    const std::vector<std::string> names = model_names();
    for (const char* n :
         {"svd", "preintegration", "guided", "manual", "deon", "ssss_skin", "test_scaled"})
        EXPECT_NE(std::find(names.begin(), names.end(), n), names.end()) << n;
    const ModelSpec s = parse_model("test_scaled:f=2");
    EXPECT_EQ(s.label(), "test_scaled_f2");
    EXPECT_TRUE(s.closed_form());  // no closed_form function: closed form
    EXPECT_EQ(s.cache_text(), "test_scaled:f=2@test-scaled-1");
    EXPECT_EQ(parse_model("svd:rank=2").cache_text(), "svd:rank=2");  // built-ins: text only
    EXPECT_FALSE(parse_model("guided:k=1").closed_form());
    EXPECT_FALSE(parse_model("manual:fit=edge").closed_form());
    EXPECT_TRUE(parse_model("manual:near=0.1,far=1,w=0.5").closed_form());

    const RadialProfile p = analytic_profile(40, 0.005, 0.015, 0.1);
    const Kernel2D k(p, 1, KernelGrid::from_profile(p));
    const ModelResult m = build_model(s, k, {"x", 1, {}});
    const ModelResult pre = preintegration(k);
    EXPECT_EQ(m.kernel.model, "test_scaled_f2");
    EXPECT_NEAR(m.kernel.sum(), 2.0 * pre.kernel.sum(), 1e-12);
    EXPECT_NEAR(m.kernel.at(3, -5), 2.0 * pre.kernel.at(3, -5), 1e-15);
}

TEST(ModelRegistry, BadRegistrationsAndSpecsAreRefusedWithTheReason) {
    register_scaled_preintegration();
    const auto refused = [](ModelFactory f, const std::string& why) {
        try {
            register_model(std::move(f));
            ADD_FAILURE() << "registered: " << why;
        } catch (const std::invalid_argument& e) {
            EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
        }
    };
    const auto build = [](const ModelSpec&, const Kernel2D& k, const ModelContext&) {
        return preintegration(k);
    };
    refused({"svd", {}, "", "v1", {}, {}, build}, "exists already");
    refused({"test_scaled", {}, "", "v1", {}, {}, build}, "exists already");
    refused({"Bad-Name", {}, "", "v1", {}, {}, build}, "is not [a-z0-9_]+");
    refused({"", {}, "", "v1", {}, {}, build}, "is not [a-z0-9_]+");
    refused({"no_build", {}, "", "v1", {}, {}, {}}, "no build");
    refused({"no_version", {}, "", "", {}, {}, build}, "a version is required");
    refused({"bad_key", {"a=b"}, "", "v1", {}, {}, build}, "the key \"a=b\"");

    // Specs: an unknown model lists every model, the registered one among them; an unknown key
    // lists the model's keys; the model's own check runs at parse time.
    try {
        parse_model("nonesuch");
        ADD_FAILURE();
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("test_scaled:f=F (a test's model)"), std::string::npos)
            << e.what();
        EXPECT_NE(std::string(e.what()).find("svd:rank=N"), std::string::npos) << e.what();
    }
    EXPECT_THROW(parse_model("test_scaled:g=1"), std::invalid_argument);
    EXPECT_THROW(parse_model("test_scaled:f=-1"), std::invalid_argument);
    EXPECT_THROW(parse_model("test_scaled:f=x"), std::invalid_argument);
    EXPECT_THROW(parse_model("test_scaled:f=1,f=2"), std::invalid_argument);
}

TEST(ModelRegistry, AModelThatBuildsOnAnotherGridIsAnError) {
    static bool done = false;
    if (!done) {
        done = true;
        ModelFactory f;
        f.name = "test_wrong_grid";
        f.version = "1";
        f.build = [](const ModelSpec&, const Kernel2D& k, const ModelContext&) {
            ModelResult r = preintegration(k);
            r.kernel.n -= 1;
            r.kernel.terms[0].a.pop_back();
            return r;
        };
        register_model(std::move(f));
    }
    const RadialProfile p = analytic_profile(40, 0.005, 0.015, 0.1);
    const Kernel2D k(p, 0, KernelGrid::from_profile(p));
    EXPECT_THROW(build_model(parse_model("test_wrong_grid"), k, {"x", 0, {}}), std::logic_error);
}

}  // namespace
}  // namespace ssslab::approx
