// Layered slabs in the volumetric path tracer: MCML's layered transport [Wang95] reproduced by an
// independent implementation. Against MCML bin by bin on stacks with mismatched indices, total
// internal reflection at an inner interface, a clear (glass) cover and per-channel anisotropy;
// against physics (energy conservation through every interface, a stack of identical layers is
// the homogeneous slab, a clear cover of the medium's own index leaves the total reflectance
// unchanged); and the layered description itself (config, MCML run, refusals).
#include "core/config.h"
#include "core/error.h"
#include "core/material.h"
#include "mcml/mci.h"
#include "mcml/profile.h"
#include "mcml/run_spec.h"
#include "testing.h"
#include "volpath/pencil.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

namespace ssslab::volpath {
namespace {

std::int64_t scaled(double paths) {
    return static_cast<std::int64_t>(paths * testing::test_scale());
}

MediumLayer layer(std::array<double, 3> sa, std::array<double, 3> ss, std::array<double, 3> g,
                  double eta, double thickness_cm) {
    return {sa, ss, g, eta, thickness_cm};
}

// A medium from layers, top first.
Medium stack(const std::string& name, const std::vector<MediumLayer>& ls, double eta_above,
             double eta_below) {
    Medium m;
    m.name = name;
    m.sigma_a_per_cm = ls[0].sigma_a_per_cm;
    m.sigma_s_per_cm = ls[0].sigma_s_per_cm;
    m.g = ls[0].g;
    m.eta = ls[0].eta;
    m.thickness_cm = ls[0].thickness_cm;
    m.lower_layers.assign(ls.begin() + 1, ls.end());
    m.eta_above = eta_above;
    m.eta_below = eta_below;
    return m;
}

// Three skin-like layers with mismatched indices and per-channel anisotropy over a half-space.
Medium skin3() {
    return stack("skin3",
                 {layer({2, 3, 5}, {40, 50, 60}, {0.8, 0.8, 0.8}, 1.45, 0.02),
                  layer({0.2, 0.5, 1.0}, {20, 25, 30}, {0.6, 0.7, 0.8}, 1.38, 0.1),
                  layer({0.5, 1, 2}, {10, 12, 15}, {0, 0, 0}, 1.44, 1e8)},
                 1.0, 1.0);
}

// A clear cover (MCML's glass layer) over a turbid half-space of a lower index.
Medium glass_cover() {
    return stack("glass-cover",
                 {layer({0, 0, 0}, {0, 0, 0}, {0, 0, 0}, 1.52, 0.05),
                  layer({0.1, 0.3, 1.0}, {10, 10, 10}, {0.5, 0.5, 0.5}, 1.33, 1e8)},
                 1.0, 1.0);
}

// A thin high-index layer over a lower-index one (total internal reflection at the inner
// interface beyond 41.7 degrees), finite, backward scattering below, a different index under it.
Medium tir_slab() {
    return stack("tir-slab",
                 {layer({0.5, 0.5, 0.5}, {30, 30, 30}, {0.3, 0.3, 0.3}, 2.0, 0.03),
                  layer({0.2, 0.4, 0.8}, {15, 15, 15}, {-0.3, -0.3, -0.3}, 1.33, 0.1)},
                 1.0, 1.2);
}

PencilRun run(const Medium& m, double paths, ChromaticMode mode, PencilGrid grid,
              std::uint64_t seed = 1) {
    PencilOptions o;
    o.budget.samples = scaled(paths);
    o.mode = mode;
    o.seed = seed;
    return simulate_pencil(m, grid, o);
}

struct BinComparison {
    double chi2 = 0, max_abs_z = 0;
    int bins = 0;
};

// Per-bin z-scores of two independent binned estimates (values and standard errors); bins with
// a relative SE above 30 % in either are left out, so Gaussian statistics apply.
BinComparison compare(const std::vector<double>& va, const std::vector<double>& sa,
                      const std::vector<double>& vb, const std::vector<double>& sb) {
    BinComparison out;
    for (size_t i = 0; i < va.size() && i < vb.size(); ++i) {
        if (!(sa[i] > 0 && sb[i] > 0) || sa[i] > 0.3 * va[i] || sb[i] > 0.3 * vb[i]) continue;
        const double z = (va[i] - vb[i]) / std::hypot(sa[i], sb[i]);
        out.chi2 += z * z;
        out.max_abs_z = std::max(out.max_abs_z, std::fabs(z));
        ++out.bins;
    }
    return out;
}

BinComparison compare(const RadialProfile& a, const RadialProfile& b, int c) {
    return compare(a.rd_per_cm2[c], a.se_per_cm2[c], b.rd_per_cm2[c], b.se_per_cm2[c]);
}

double z_score(double a, double sa, double b, double sb) {
    return (a - b) / std::hypot(sa, sb);
}

// ---- the layered description ------------------------------------------------------------------

TEST(LayeredMedium, ConfigReadsLayersTopFirstWithUnits) {
    auto doc = ConfigDocument::parse_string(
        "[material]\nname = \"s\"\neta_above = 1.1\neta_below = 1.2\n"
        "[[material.layers]]\nsigma_a_per_mm = [0.2, 0.3, 0.5]\nsigma_s_per_mm = [4, 5, 6]\n"
        "g = 0.8\neta = 1.45\nthickness_mm = 0.2\n"
        "[[material.layers]]\npreset = \"Skin1\"\nthickness_cm = 0.1\n"
        "[[material.layers]]\nsigma_a_per_cm = [1, 2, 3]\nsigma_s_per_cm = [10, 10, 10]\n"
        "eta = 1.3\n",
        "layers.toml");
    ConfigTable t = doc->root().require_table("material");
    const Medium m = medium_from_config(t);
    doc->root().finish();
    ASSERT_TRUE(m.layered());
    const std::vector<MediumLayer> ls = m.layers();
    ASSERT_EQ(ls.size(), 3u);
    EXPECT_DOUBLE_EQ(ls[0].sigma_a_per_cm[2], 5.0);  // 0.5 / mm
    EXPECT_DOUBLE_EQ(ls[0].sigma_s_per_cm[0], 40.0);
    EXPECT_DOUBLE_EQ(ls[0].thickness_cm, 0.02);
    EXPECT_EQ(ls[0].g[1], 0.8);
    const Medium skin = *find_material("Skin1");
    EXPECT_EQ(ls[1].sigma_a_per_cm, skin.sigma_a_per_cm);
    EXPECT_EQ(ls[1].eta, skin.eta);
    EXPECT_DOUBLE_EQ(ls[1].thickness_cm, 0.1);
    EXPECT_EQ(ls[2].thickness_cm, 1e8);  // the last layer defaults to quasi-infinite
    EXPECT_EQ(m.eta_above, 1.1);
    EXPECT_EQ(m.eta_below, 1.2);
    EXPECT_DOUBLE_EQ(m.total_thickness_cm(), 0.12 + 1e8);
}

TEST(LayeredMedium, BadStacksAreRefusedWithFileLineAndKey) {
    struct Case {
        const char* text;
        const char* expect;  // in the message
    };
    const Case cases[] = {
        // A middle layer without a thickness.
        {"[m]\n[[m.layers]]\npreset = \"Apple\"\n[[m.layers]]\npreset = \"Skin1\"\n",
         "bad.toml:2:1: error: key 'm.layers[0].thickness_mm'"},
        // Coefficients beside the layers.
        {"[m]\neta = 1.3\n[[m.layers]]\npreset = \"Apple\"\n", "bad.toml:2:7: error: key 'm.eta'"},
        // A quasi-infinite middle layer.
        {"[m]\n[[m.layers]]\npreset = \"Apple\"\nthickness_cm = 1e9\n[[m.layers]]\n"
         "preset = \"Skin1\"\n",
         "only the last layer may be quasi-infinite"},
        // A negative coefficient in a layer.
        {"[m]\n[[m.layers]]\nsigma_a_per_mm = [0.1, -1, 0.1]\nsigma_s_per_mm = [1, 1, 1]\n"
         "eta = 1.3\n",
         "bad.toml:3"},
        // No layers at all.
        {"[m]\nlayers = []\n", "expected an array of tables"},
        // An unknown key inside a layer is caught at finish().
        {"[m]\n[[m.layers]]\npreset = \"Apple\"\nthickness_mn = 1\n", "thickness_mn"},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.text);
        try {
            auto doc = ConfigDocument::parse_string(c.text, "bad.toml");
            ConfigTable t = doc->root().require_table("m");
            (void)medium_from_config(t);
            doc->root().finish();
            ADD_FAILURE() << "accepted";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(c.expect), std::string::npos) << e.what();
        }
    }
}

TEST(LayeredMedium, McmlRunEqualsTheSameStackReadFromAnMci) {
    // run_for_channel's layers against the .mci reader (an independent path into a RunSpec).
    const Medium m = tir_slab();
    const mcml::Grid g{0.01, 0.005, 10, 80, 1};
    const mcml::RunSpec a = mcml::run_for_channel(m, 2, 1000, g);
    const mcml::MciFile f = mcml::parse_mci(
        "1.0\n1\ntir.mco A\n1000\n0.01 0.005\n10 80 1\n2\n1.0\n"
        "2.0 0.5 30 0.3 0.03\n"  // n mua mus g d, channel B of the stack
        "1.33 0.8 15 -0.3 0.1\n1.2\n",
        "tir.mci");
    const mcml::RunSpec& b = f.runs.at(0);
    ASSERT_EQ(a.layers.size(), b.layers.size());
    for (size_t i = 0; i < a.layers.size(); ++i) {
        SCOPED_TRACE(i);
        EXPECT_EQ(a.layers[i].n, b.layers[i].n);
        EXPECT_EQ(a.layers[i].mua, b.layers[i].mua);
        EXPECT_EQ(a.layers[i].mus, b.layers[i].mus);
        EXPECT_EQ(a.layers[i].g, b.layers[i].g);
        if (i == 0 || i + 1 == a.layers.size()) continue;  // ambient media: only n is used
        EXPECT_NEAR(a.layers[i].z0, b.layers[i].z0, 1e-15);
        EXPECT_NEAR(a.layers[i].z1, b.layers[i].z1, 1e-15);
        EXPECT_EQ(a.layers[i].cos_crit0, b.layers[i].cos_crit0);
        EXPECT_EQ(a.layers[i].cos_crit1, b.layers[i].cos_crit1);
    }
    // Snell: the critical angle of 2.0 -> 1.33 at the inner interface.
    EXPECT_NEAR(a.layers[1].cos_crit1, std::sqrt(1 - std::pow(1.33 / 2.0, 2)), 1e-15);
}

TEST(LayeredMedium, HomogeneousOnlyModelsRefuseStacks) {
    EXPECT_THROW(require_homogeneous(skin3(), "the dipole"), std::invalid_argument);
    EXPECT_NO_THROW(require_homogeneous(*find_material("Skin1"), "the dipole"));
    // A top layer clear in some channels only has no channel-independent entry.
    Medium m = glass_cover();
    m.sigma_s_per_cm[1] = 1.0;
    EXPECT_THROW(check_pencil(m, {0.01, 10}), std::invalid_argument);
    // A quasi-infinite layer in the middle, and a clear half-space at the bottom.
    Medium mid = skin3();
    mid.lower_layers[0].thickness_cm = 1e8;
    EXPECT_THROW(check_pencil(mid, {0.01, 10}), std::invalid_argument);
    Medium clear_bottom = skin3();
    clear_bottom.lower_layers[1].sigma_a_per_cm = {0, 0, 0};
    clear_bottom.lower_layers[1].sigma_s_per_cm = {0, 0, 0};
    EXPECT_THROW(check_pencil(clear_bottom, {0.01, 10}), InfeasibleError);
}

// ---- physics ------------------------------------------------------------------------------------

TEST(VolpathLayers, WhiteFurnaceThroughMismatchedInterfaces) {
    // Albedo 1 in every layer of a finite stack with indices 2.0 / 1.33 / 1.6 between 1.0 and
    // 1.2, and a clear layer in the middle: nothing is absorbed, so in analog mode each path
    // leaves with weight 1 - Rsp through the top or the bottom and R + T = 1 - Rsp exactly; in
    // hero mode (chromatic, per-channel g) within its standard error.
    Medium m = stack("white",
                     {layer({0, 0, 0}, {30, 30, 30}, {0.3, 0.3, 0.3}, 2.0, 0.03),
                      layer({0, 0, 0}, {0, 0, 0}, {0, 0, 0}, 1.33, 0.02),
                      layer({0, 0, 0}, {15, 15, 15}, {-0.3, -0.3, -0.3}, 1.6, 0.1)},
                     1.0, 1.2);
    const PencilRun a = run(m, 2e4, ChromaticMode::kPerChannel, {0.01, 40});
    const double rsp = entry_specular(m);
    EXPECT_NEAR(rsp, 1.0 / 9.0, 1e-15);  // (1 - 2)^2 / (1 + 2)^2
    for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(a.profile.rd_total[c] + a.tt[c], 1.0 - rsp, 1e-12);
        EXPECT_GT(a.tt[c], 0.05);
        EXPECT_GT(a.profile.rd_total[c], 0.05);
    }
    m.sigma_s_per_cm = {5, 30, 90};
    m.g = {0.0, 0.5, 0.9};
    const PencilRun h = run(m, 3e4, ChromaticMode::kHero, {0.01, 40});
    for (int c = 0; c < 3; ++c) {
        const double sum = h.profile.rd_total[c] + h.tt[c];
        // The per-path sum varies with the MIS weights; its SE is at most the sum of the SEs.
        EXPECT_LT(std::fabs(sum - (1 - rsp)), 4 * (h.profile.rd_total_se[c] + h.tt_se[c]))
            << kChannelNames[c] << ": " << sum;
    }
}

TEST(VolpathLayers, IdenticalLayersAreTheHomogeneousSlab) {
    // Interfaces between equal media must be invisible: Skin1 cut into 0.05 + 0.1 cm + a
    // half-space equals Skin1 (an independent seed), bin by bin, per channel and in hero mode.
    const Medium skin = *find_material("Skin1");
    MediumLayer l{skin.sigma_a_per_cm, skin.sigma_s_per_cm, skin.g, skin.eta, 0.05};
    MediumLayer l2 = l, l3 = l;
    l2.thickness_cm = 0.1;
    l3.thickness_cm = 1e8;
    const Medium cut = stack("Skin1-cut", {l, l2, l3}, 1.0, 1.0);
    const PencilGrid grid{0.01, 60};
    const double alpha = testing::sidak(0.001, 6);
    for (ChromaticMode mode : {ChromaticMode::kPerChannel, ChromaticMode::kHero}) {
        SCOPED_TRACE(to_string(mode));
        const PencilRun a = run(skin, 5e4, mode, grid, 11);
        const PencilRun b = run(cut, 5e4, mode, grid, 12);
        for (int c = 0; c < 3; ++c) {
            const BinComparison cmp = compare(a.profile, b.profile, c);
            EXPECT_GT(cmp.bins, 20);
            EXPECT_LT(cmp.chi2, testing::chi2_critical(cmp.bins, alpha)) << kChannelNames[c];
            EXPECT_LT(std::fabs(z_score(a.profile.rd_total[c], a.profile.rd_total_se[c],
                                        b.profile.rd_total[c], b.profile.rd_total_se[c])),
                      4.0);
        }
    }
}

TEST(VolpathLayers, ClearCoverOfTheSameIndexKeepsTheTotalReflectance) {
    // A clear 2 mm cover with the medium's own index moves the exit points outwards but, over a
    // half-space (invariant under lateral shifts), cannot change how much light leaves: the
    // cover's top sees the same angles the bare surface would. Rsp is the same (r2 = 0).
    const Medium skin = *find_material("Skin1");
    const Medium covered =
        stack("covered",
              {layer({0, 0, 0}, {0, 0, 0}, {0, 0, 0}, skin.eta, 0.2),
               layer(skin.sigma_a_per_cm, skin.sigma_s_per_cm, skin.g, skin.eta, 1e8)},
              1.0, 1.0);
    EXPECT_DOUBLE_EQ(entry_specular(covered), entry_specular(skin));
    const PencilGrid grid{0.02, 100};
    const PencilRun a = run(skin, 5e4, ChromaticMode::kPerChannel, grid, 21);
    const PencilRun b = run(covered, 5e4, ChromaticMode::kPerChannel, grid, 22);
    for (int c = 0; c < 3; ++c) {
        SCOPED_TRACE(kChannelNames[c]);
        const double ta = a.profile.rd_total[c];
        EXPECT_LT(std::fabs(z_score(ta, a.profile.rd_total_se[c], b.profile.rd_total[c],
                                    b.profile.rd_total_se[c])),
                  4.0)
            << ta << " vs " << b.profile.rd_total[c];
        // ... but the profile is not the same: less light in the first bins under the cover.
        EXPECT_GT(a.profile.rd_per_cm2[c][0], 2 * b.profile.rd_per_cm2[c][0]);
    }
}

// ---- against MCML -------------------------------------------------------------------------------

TEST(VolpathLayers, AgreesWithMcmlOnLayeredStacks) {
    // Three stacks, three channels: R_d(r) bin by bin (chi-square, Sidak-corrected over the nine
    // comparisons; every bin within the matching normal quantile), total diffuse reflectance
    // and, for the finite stack, transmittance as z-scores.
    const double alpha = testing::sidak(0.001, 9);
    int total_bins = 0;
    double total_chi2 = 0;
    for (const Medium& m : {skin3(), glass_cover(), tir_slab()}) {
        SCOPED_TRACE(m.name);
        const mcml::ProfileGrid g{0.005, 80};
        mcml::ProfileOptions mo;
        mo.budget.samples = scaled(1e5);
        mo.seed = 7;
        const mcml::ProfileRun ref = mcml::simulate_profile(m, g, mo);
        const PencilRun vp = run(m, 1e5, ChromaticMode::kPerChannel, {g.dr_cm, g.nr}, 8);
        for (int c = 0; c < 3; ++c) {
            SCOPED_TRACE(kChannelNames[c]);
            const BinComparison cmp = compare(vp.profile, ref.profile, c);
            total_bins += cmp.bins;
            total_chi2 += cmp.chi2;
            EXPECT_GT(cmp.bins, 40);
            EXPECT_LT(cmp.chi2, testing::chi2_critical(cmp.bins, alpha)) << cmp.bins << " bins";
            EXPECT_LT(cmp.max_abs_z, testing::normal_quantile(1 - 0.5 * alpha / cmp.bins));
            EXPECT_EQ(vp.profile.rsp[c], ref.profile.rsp[c]);
            EXPECT_LT(std::fabs(z_score(vp.profile.rd_total[c], vp.profile.rd_total_se[c],
                                        ref.profile.rd_total[c], ref.profile.rd_total_se[c])),
                      4.0)
                << vp.profile.rd_total[c] << " vs " << ref.profile.rd_total[c];
            const mcml::RunResult& r = ref.channels[static_cast<size_t>(c)];
            if (m.total_thickness_cm() < 1e8) {
                EXPECT_LT(std::fabs(z_score(vp.tt[c], vp.tt_se[c], r.mean(r.layout.tt),
                                            r.se[r.layout.tt])),
                          4.0)
                    << vp.tt[c] << " vs " << r.mean(r.layout.tt);
                EXPECT_GT(vp.tt[c], 0.05);
            }
        }
        std::printf("%s: Rd R %.5f +- %.5f (MCML %.5f +- %.5f)\n", m.name.c_str(),
                    vp.profile.rd_total[0], vp.profile.rd_total_se[0], ref.profile.rd_total[0],
                    ref.profile.rd_total_se[0]);
    }
    std::printf("layered stacks vs MCML: chi2 %.1f over %d bins\n", total_chi2, total_bins);
}

TEST(VolpathLayers, HeroModeAgreesWithPerChannelRunsOnAStack) {
    // Hero paths (analog and weighted) cross layers whose extinction differs per channel: the
    // MIS densities carry the optical depth of every layer crossed.
    const Medium m = skin3();
    const PencilGrid grid{0.005, 80};
    const PencilRun a = run(m, 1e5, ChromaticMode::kPerChannel, grid, 31);
    const PencilRun h = run(m, 1e5, ChromaticMode::kHero, grid, 32);
    PencilOptions wo;
    wo.budget.samples = scaled(1e5);
    wo.mode = ChromaticMode::kHero;
    wo.absorption = Absorption::kWeighted;
    wo.seed = 33;
    const PencilRun hw = simulate_pencil(m, grid, wo);
    const double alpha = testing::sidak(0.001, 6);
    for (int c = 0; c < 3; ++c) {
        SCOPED_TRACE(kChannelNames[c]);
        const BinComparison cw = compare(a.profile, hw.profile, c);
        EXPECT_LT(cw.chi2, testing::chi2_critical(cw.bins, alpha)) << cw.bins << " bins";
        const BinComparison cmp = compare(a.profile, h.profile, c);
        EXPECT_GT(cmp.bins, 40);
        EXPECT_LT(cmp.chi2, testing::chi2_critical(cmp.bins, alpha)) << cmp.bins << " bins";
        EXPECT_LT(std::fabs(z_score(a.profile.rd_total[c], a.profile.rd_total_se[c],
                                    h.profile.rd_total[c], h.profile.rd_total_se[c])),
                  4.0);
    }
}

}  // namespace
}  // namespace ssslab::volpath
