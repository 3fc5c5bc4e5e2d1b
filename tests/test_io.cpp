// Inputs and outputs: .mci parsing (as the original, and where the original fails), .mco layout,
// profile CSV, configs and their resolved form, atomic output, material presets.
#include "core/atomic_file.h"
#include "core/config.h"
#include "core/error.h"
#include "core/format.h"
#include "core/material.h"
#include "core/profile.h"
#include "mcml/mci.h"
#include "mcml/mco.h"
#include "mcml/tally.h"
#include "mcml/transport.h"
#include "testing.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>

namespace ssslab {
namespace {

const char* kTemplate =
    "####\n"
    "# Template of input files for Monte Carlo simulation (mcml).\n"
    "####\n"
    "\n"
    "1.0\t\t\t\t\t\t# file version\n"
    "2\t\t\t\t\t\t# number of runs\n"
    "\n"
    "### Specify data for run 1\n"
    "temp1.mco\tA\t\t\t\t# output filename, ASCII/Binary\n"
    "10\t\t\t\t\t\t# No. of photons\n"
    "20E-4\t20E-4\t\t\t\t\t# dz, dr\n"
    "10\t20\t30\t\t\t\t# No. of dz, dr & da.\n"
    "\n"
    "2\t\t\t\t\t\t# No. of layers\n"
    "# n\tmua\tmus\tg\td\t\t# One line for each layer\n"
    "1.0\t\t\t\t\t\t# n for medium above.\n"
    "1.3\t20\t200\t0.70\t0.01\t\t# layer 1\n"
    "1.4\t10\t200\t0.90\t1.0E+8\t\t# layer 2\n"
    "1.0\t\t\t\t\t\t# n for medium below.\n"
    "\n"
    "### Specify data for run 2\n"
    "temp2.mco\tA\t\t\t\t# output filename, ASCII/Binary\n"
    "20\t\t\t\t\t\t# No. of photons\n"
    "20E-4\t20E-4\t\t\t\t\t# dz, dr\n"
    "80\t80\t30\t\t\t\t# No. of dz, dr & da.\n"
    "\n"
    "1\t\t\t\t\t\t# No. of layers\n"
    "# n\tmua\tmus\tg\td\t\t# One line for each layer\n"
    "1.0\t\t\t\t\t\t# n for medium above.\n"
    "1.4\t10\t200\t0.70\t1.0E+8\t\t# layer 1\n"
    "1.0\t\t\t\t\t\t# n for medium below.\n";

TEST(NumbersAsText, SeventeenDigitsReadBackAndFixedTextIsWhole) {
    // printf's conversions (C11 7.21.6.1): %.17g of 0.1 shows the double's error; %.6g rounds.
    EXPECT_EQ(format_g(0.1), "0.10000000000000001");
    EXPECT_EQ(format_g(1234.5678, 6), "1234.57");
    EXPECT_EQ(format_g(-2.5e-7, 3), "-2.5e-07");
    // 17 significant digits identify every double (IEEE 754-2008 5.12.2): strtod gives it back,
    // subnormals and the extremes included.
    for (double v : {1.0 / 3, 4.9406564584124654e-324, 2.2250738585072014e-308,
                     1.7976931348623157e308, -0.0, 3.141592653589793, 1e-300, 6.02214076e23}) {
        const double back = std::strtod(format_g(v).c_str(), nullptr);
        EXPECT_EQ(std::memcmp(&back, &v, sizeof v), 0) << format_g(v);
    }
    // Fixed notation: ties go to even in the binary value (0.125 is exact), and a long number
    // keeps every digit: 1e300 with two decimals is 301 digits, the point and 2 more.
    EXPECT_EQ(format_f(0.125, 2), "0.12");
    EXPECT_EQ(format_f(-1.5, 0), "-2");
    const std::string big = format_f(1e300, 2);
    EXPECT_EQ(big.size(), 304u);
    EXPECT_EQ(big.substr(big.size() - 3), ".00");
    EXPECT_EQ(std::strtod(big.c_str(), nullptr), 1e300);
}

TEST(Mci, ParsesTheOriginalTemplate) {
    const mcml::MciFile f = mcml::parse_mci(kTemplate, "template.mci");
    ASSERT_EQ(f.runs.size(), 2u);
    const mcml::RunSpec& r = f.runs[0];
    EXPECT_EQ(r.out_name, "temp1.mco");
    EXPECT_EQ(r.out_format, 'A');
    EXPECT_EQ(r.photons, 10);
    EXPECT_DOUBLE_EQ(r.grid.dz, 20e-4);
    EXPECT_EQ(r.grid.nz, 10);
    EXPECT_EQ(r.grid.nr, 20);
    EXPECT_EQ(r.grid.na, 30);
    ASSERT_EQ(r.num_layers(), 2);
    EXPECT_DOUBLE_EQ(r.layers[1].z1, 0.01);
    EXPECT_DOUBLE_EQ(r.layers[2].z0, 0.01);
    EXPECT_DOUBLE_EQ(r.layers[2].z1, 0.01 + 1e8);
    EXPECT_DOUBLE_EQ(r.layers[2].g, 0.9);
    EXPECT_EQ(r.layers[2].source_line, 18);
    // Critical angles as MCML's CriticalAngle(): layer 1 (1.3) under air (1.0).
    EXPECT_DOUBLE_EQ(r.layers[1].cos_crit0, std::sqrt(1.0 - 1.0 / (1.3 * 1.3)));
    EXPECT_EQ(r.layers[1].cos_crit1, 0.0);  // 1.3 above 1.4: no total internal reflection
    EXPECT_EQ(f.runs[1].photons, 20);
}

TEST(Mci, CrlfFilesParseLikeLfFiles) {
    std::string crlf;
    for (char c : std::string(kTemplate))
        crlf += c == '\n' ? std::string("\r\n") : std::string(1, c);
    const mcml::MciFile a = mcml::parse_mci(kTemplate, "lf.mci");
    const mcml::MciFile b = mcml::parse_mci(crlf, "crlf.mci");
    ASSERT_EQ(a.runs.size(), b.runs.size());
    EXPECT_EQ(mcml::format_mci(a.runs), mcml::format_mci(b.runs));
}

TEST(Mci, FormatRoundTrips) {
    const mcml::MciFile a = mcml::parse_mci(kTemplate, "t.mci");
    const mcml::MciFile b = mcml::parse_mci(mcml::format_mci(a.runs), "again.mci");
    EXPECT_EQ(mcml::format_mci(a.runs), mcml::format_mci(b.runs));
    EXPECT_EQ(b.runs[0].layers[2].z1, a.runs[0].layers[2].z1);
}

TEST(Mci, NegativeGIsAnExtensionOfTheDefaultMode) {
    std::string text = kTemplate;
    text.replace(text.find("0.70\t0.01"), 4, "-0.7");
    EXPECT_NO_THROW(mcml::parse_mci(text, "neg.mci"));
    try {
        mcml::parse_mci(text, "neg.mci", {.allow_negative_g = false});
        FAIL() << "g < 0 accepted in compatibility mode";
    } catch (const InputError& e) {
        EXPECT_EQ(e.where().line, 17);
        EXPECT_NE(std::string(e.what()).find("g < 0"), std::string::npos) << e.what();
    }
}

TEST(Mco, CountsOutOfRangeAreRefusedNotCast) {
    // Found by fuzz/fuzz_mco.cpp (fuzz/regressions/mco/): an infinite or fractional grid size,
    // photon or layer count was cast to an integer (undefined behaviour).
    const mcml::MciFile f = mcml::parse_mci(kTemplate, "t.mci");
    const mcml::RunSpec& run = f.runs[0];
    const mcml::TallyLayout L = mcml::TallyLayout::make(run, mcml::TallyMode::kFull);
    std::vector<double> raw(L.size, 1.0);
    mcml::reduce(run, raw.data(), L);
    const std::string good =
        mcml::format_mco(run, mcml::scale_full(run, raw, L, 1000.0, mcml::kPi, 0.05), 1000, 1.0);
    const std::string grid = std::to_string(run.grid.nz) + "\t" + std::to_string(run.grid.nr);
    const size_t at = good.find(grid);
    ASSERT_NE(at, std::string::npos);
    for (const char* bad : {"inf", "1e300", "2.5", "-3", "0"}) {
        std::string text = good;
        text.replace(at, std::to_string(run.grid.nz).size(), bad);
        try {
            (void)mcml::parse_mco(text, "t.mco");
            ADD_FAILURE() << "nz = " << bad << " was accepted";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find("nz must be a whole number"), std::string::npos)
                << e.what();
            EXPECT_GT(e.where().line, 0);
        }
    }
    EXPECT_THROW((void)mcml::parse_mco(
                     testing::read_text(testing::source_path("fuzz/regressions/mco/nz-inf.mco")),
                     "nz-inf.mco"),
                 InputError);
}

TEST(Mco, WriterAndReaderAgree) {
    const mcml::MciFile f = mcml::parse_mci(kTemplate, "t.mci");
    const mcml::RunSpec& run = f.runs[0];
    const mcml::TallyLayout L = mcml::TallyLayout::make(run, mcml::TallyMode::kFull);
    std::vector<double> raw(L.size, 0.0);
    for (size_t i = 0; i < L.primary_size; ++i) raw[i] = 1.0 + static_cast<double>(i % 7);
    mcml::reduce(run, raw.data(), L);
    const mcml::McoResult v = mcml::scale_full(run, raw, L, 1000.0, mcml::kPi, 0.05);
    const std::string text = mcml::format_mco(run, v, 1000, 12.0);
    const mcml::McoFile back = mcml::parse_mco(text, "t.mco");
    EXPECT_EQ(back.photons, 1000);
    EXPECT_EQ(back.grid.nr, run.grid.nr);
    EXPECT_EQ(back.num_layers, 2);
    EXPECT_NEAR(back.result.rd, v.rd, 1e-6 * v.rd);
    ASSERT_EQ(back.result.a_rz.size(), v.a_rz.size());
    for (size_t i = 0; i < v.a_rz.size(); ++i)
        EXPECT_NEAR(back.result.a_rz[i], v.a_rz[i], 1e-4 * v.a_rz[i]);  // "%12.4E"
    // Sections in the original's order.
    size_t pos = 0;
    for (const char* section : {"InParm", "RAT", "A_l", "A_z", "Rd_r", "Rd_a", "Tt_r", "Tt_a",
                                "A_rz", "Rd_ra", "Tt_ra"}) {
        const size_t at = text.find(std::string("\n") + section, pos);
        ASSERT_NE(at, std::string::npos) << section;
        pos = at + 1;
    }
    // The scaled 1D profile is the 2D array summed over angles, divided by the annulus area.
    const double area = 2 * mcml::kPi * (0 + 0.5) * run.grid.dr * run.grid.dr * 1000.0;
    double sum = 0;
    for (int ia = 0; ia < run.grid.na; ++ia) sum += raw[L.rd_ra + static_cast<size_t>(ia)];
    EXPECT_NEAR(v.rd_r[0], sum / area, 1e-12 * v.rd_r[0]);
}

TEST(Profile, CsvRoundTripsInBothUnits) {
    RadialProfile p;
    p.name = "x";
    p.dr_cm = 0.01;
    p.nr = 4;
    for (int c = 0; c < 3; ++c) {
        p.rd_per_cm2[c] = {4.0 + c, 3.0, 2.0, 1.0};
        p.se_per_cm2[c] = {0.1, 0.1, 0.2, 0.3};
    }
    testing::TempDir dir;
    for (LengthUnit u : {LengthUnit::kCm, LengthUnit::kMm}) {
        const auto path = dir.write(std::string("p_") + unit_name(u) + ".csv", p.to_csv(u));
        const RadialProfile q = read_profile_csv(path.string());
        EXPECT_EQ(q.nr, 4);
        EXPECT_NEAR(q.dr_cm, 0.01, 1e-12);
        for (int c = 0; c < 3; ++c)
            for (int i = 0; i < 4; ++i)
                EXPECT_NEAR(q.rd_per_cm2[c][static_cast<size_t>(i)],
                            p.rd_per_cm2[c][static_cast<size_t>(i)], 1e-7);
    }
    // Header states the units.
    EXPECT_EQ(p.to_csv(LengthUnit::kMm).substr(0, 40).find("r_mid_mm,r_lo_mm,r_hi_mm,Rd_R_per_mm2"),
              0u);
}

TEST(Config, ResolvedConfigurationHasEveryDefault) {
    auto doc = ConfigDocument::parse_string("[material]\npreset = \"Skin1\"\n", "c.toml");
    ConfigTable root = doc->root();
    ConfigTable m = root.require_table("material");
    const Medium med = medium_from_config(m);
    EXPECT_EQ(med.name, "Skin1");
    EXPECT_EQ(root.integer("seed", 1, Range::nonnegative()), 1);
    root.finish();
    const std::string resolved = doc->resolved_toml();
    for (const char* key : {"preset = 'Skin1'", "seed = 1", "eta_above = 1.0", "thickness_cm"})
        EXPECT_NE(resolved.find(key), std::string::npos) << key << " in\n" << resolved;
}

TEST(Config, ExplicitCoefficientsConvertUnitsInOnePlace) {
    auto doc = ConfigDocument::parse_string(
        "[material]\nsigma_a_per_mm = [0.032, 0.17, 0.48]\nsigma_s_per_mm = [0.74, 0.88, 1.01]\n"
        "g = -0.2\neta = 1.3\nthickness_mm = 5\n",
        "c.toml");
    ConfigTable m = doc->root().require_table("material");
    const Medium med = medium_from_config(m);
    const Medium skin = *find_material("Skin1");
    for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(med.sigma_a_per_cm[c], skin.sigma_a_per_cm[c], 1e-12);  // JimenezSupp §G
        EXPECT_NEAR(med.sigma_s_per_cm[c], skin.sigma_s_per_cm[c], 1e-12);
        EXPECT_EQ(med.g[c], -0.2);
    }
    EXPECT_DOUBLE_EQ(med.thickness_cm, 0.5);
    doc->root().finish();
}

TEST(Config, UnknownKeysSuggestTheNearestKnownKey) {
    auto doc =
        ConfigDocument::parse_string("[material]\npreset = \"Apple\"\netaa_above = 1\n", "c.toml");
    ConfigTable m = doc->root().require_table("material");
    (void)medium_from_config(m);
    try {
        doc->root().finish();
        FAIL() << "unknown key accepted";
    } catch (const InputError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("c.toml:3:1"), std::string::npos) << msg;
        EXPECT_NE(msg.find("did you mean 'eta_above'"), std::string::npos) << msg;
        EXPECT_NE(msg.find("etaa_above = 1"), std::string::npos) << msg;  // the line, shown
    }
}

TEST(AtomicOutput, AnAbortedTransactionLeavesNothing) {
    testing::TempDir dir;
    {
        OutputTransaction tx;
        tx.stage(dir / "a.txt", "a");
        tx.stage(dir / "sub" / "b.txt", "b");
        EXPECT_FALSE(std::filesystem::exists(dir / "a.txt"));
    }
    for (const auto& f : dir.files()) ADD_FAILURE() << "left behind: " << f;
    {
        OutputTransaction tx;
        tx.stage(dir / "a.txt", "a");
        tx.commit();
    }
    EXPECT_EQ(dir.files(), std::vector<std::string>{"a.txt"});
    write_file_atomic(dir / "a.txt", "replaced");
    EXPECT_EQ(testing::read_text(dir / "a.txt"), "replaced");
    EXPECT_EQ(dir.files().size(), 1u);
}

TEST(Materials, Freude14Table62) {
    ASSERT_EQ(freude14_materials().size(), 11u);
    const Medium marble = *find_material("marble");  // case-insensitive
    EXPECT_EQ(marble.eta, 1.5);
    for (const auto& p : freude14_materials()) {
        if (std::string(p.name) != "Marble") {
            EXPECT_EQ(p.medium.eta, 1.3) << p.name;
        }
        EXPECT_EQ(p.medium.thickness_cm, 1e8);
    }
    // The stiff case the issue names: Cream's red albedo 0.99997.
    EXPECT_NEAR(find_material("Cream")->albedo(0), 0.99997, 5e-6);
    EXPECT_FALSE(find_material("Skin3").has_value());
}

}  // namespace
}  // namespace ssslab
