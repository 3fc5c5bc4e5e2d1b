// `ssslab bench --volpath`: the volumetric path tracer against MCML's default engine on the same
// slabs, its chromatic modes against each other, and the lit sphere.
//
// For each case and engine: paths per millisecond, ns per scattering event, and the time each
// would need to reach 1 % relative standard error, both for the total diffuse reflectance and
// for the r R(r) profile as a whole (relative L2 norm of the bins' standard errors). Times to a
// target are extrapolated from the measured variance with the 1/N law; the efficiency
// 1 / (relative variance x time) is their inverse. All rows of a case are measured in one
// process, one after the other, so ratios between them are what the table is for.
#include "core/material.h"
#include "experiments/cli/bench_volpath.h"
#include "mcml/engine.h"
#include "mcml/profile.h"
#include "volpath/pencil.h"
#include "volpath/sphere.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace ssslab::cli {

namespace {

struct Row {
    std::string engine;
    double seconds = 0;
    std::uint64_t paths = 0, events = 0;
    // Per channel: Rd, its SE, and the profile's relative L2 standard error.
    std::vector<double> rd, rd_se, profile_rel_se;
};

double profile_rel_se(const RadialProfile& p, int c) {
    double num = 0, den = 0;
    for (int i = 0; i < p.nr; ++i) {
        const double w = (i + 0.5);  // r R(r) weighting: bin weight ~ r R dr
        num += w * w * p.se_per_cm2[c][static_cast<size_t>(i)] *
               p.se_per_cm2[c][static_cast<size_t>(i)];
        den += w * w * p.rd_per_cm2[c][static_cast<size_t>(i)] *
               p.rd_per_cm2[c][static_cast<size_t>(i)];
    }
    return den > 0 ? std::sqrt(num / den) : 0.0;
}

Row from_profile(const std::string& engine, const RadialProfile& p, int channels, double seconds,
                 std::uint64_t paths, std::uint64_t events) {
    Row r;
    r.engine = engine;
    r.seconds = seconds;
    r.paths = paths;
    r.events = events;
    for (int c = 0; c < channels; ++c) {
        r.rd.push_back(p.rd_total[c]);
        r.rd_se.push_back(p.rd_total_se[c]);
        r.profile_rel_se.push_back(profile_rel_se(p, c));
    }
    return r;
}

// Time to reach `target` relative SE in every channel, from a run of `seconds` that reached
// `rel`: channels of separate runs each run to their own target (sum); one run for all channels
// runs until the worst channel meets it.
double time_to(double seconds, const std::vector<double>& rel, bool separate, double target) {
    double t = 0;
    const double per_channel = seconds / (separate ? static_cast<double>(rel.size()) : 1.0);
    for (double x : rel) {
        const double f = (x / target) * (x / target);
        t = separate ? t + per_channel * f : std::max(t, seconds * f);
    }
    return t;
}

/// A pencil beam case: the medium, MCML's grid, the paths per channel.
struct Case {
    std::string name;
    Medium medium;
    mcml::ProfileGrid grid;
    std::int64_t photons;
};

/// The cases: van de Hulst's slab and two measured half-spaces, at `q` times the full budget.
std::vector<Case> bench_cases(double q) {
    Medium vdh;
    vdh.name = "vdH slab";
    vdh.sigma_a_per_cm = {10, 10, 10};
    vdh.sigma_s_per_cm = {90, 90, 90};
    vdh.g = {0.75, 0.75, 0.75};
    vdh.thickness_cm = 0.02;
    const Medium skin = *find_material("Skin1");
    const Medium ketchup = *find_material("Ketchup");
    return {
        {"van de Hulst slab (tau 2, a 0.9, g 0.75)",
         vdh,
         {0.001, 50},
         static_cast<std::int64_t>(1'000'000 * q)},
        {"Skin1 half-space, Table 6.1 grid", skin, mcml::freude14_grid(skin),
         static_cast<std::int64_t>(200'000 * q)},
        {"Ketchup half-space, Table 6.1 grid", ketchup, mcml::freude14_grid(ketchup),
         static_cast<std::int64_t>(200'000 * q)},
    };
}

/// MCML's default engine and every volpath mode on one case, the fastest of `repeat` runs each.
std::vector<Row> case_rows(const Case& cs, int threads, int repeat) {
    std::vector<Row> rows;
    auto best = [&](auto&& f) {
        Row r = f();
        for (int k = 1; k < repeat; ++k) {
            Row again = f();
            if (again.seconds < r.seconds) r = std::move(again);
        }
        return r;
    };
    rows.push_back(best([&] {
        mcml::ProfileOptions o;
        o.threads = threads;
        o.budget.samples = cs.photons;
        const mcml::ProfileRun r = mcml::simulate_profile(cs.medium, cs.grid, o);
        double s = 0;
        std::uint64_t paths = 0, events = 0;
        for (const auto& ch : r.channels) {
            s += ch.seconds;
            paths += ch.photons;
            events += ch.events;
        }
        return from_profile("mcml (per channel)", r.profile, 3, s, paths, events);
    }));
    struct Mode {
        const char* name;
        volpath::ChromaticMode mode;
        volpath::Absorption absorption;
        volpath::HeroSelection selection;
    };
    using CM = volpath::ChromaticMode;
    using AB = volpath::Absorption;
    using HS = volpath::HeroSelection;
    const Mode modes[] = {{"volpath analog", CM::kPerChannel, AB::kAnalog, HS::kUniform},
                          {"volpath weighted", CM::kPerChannel, AB::kWeighted, HS::kUniform},
                          {"volpath hero", CM::kHero, AB::kAnalog, HS::kUniform},
                          {"volpath hero mfp", CM::kHero, AB::kAnalog, HS::kMeanFreePath},
                          {"volpath hero wtd", CM::kHero, AB::kWeighted, HS::kUniform}};
    for (const Mode& md : modes) {
        rows.push_back(best([&] {
            volpath::PencilOptions o;
            o.threads = threads;
            o.mode = md.mode;
            o.absorption = md.absorption;
            o.hero_selection = md.selection;
            o.budget.samples = cs.photons;
            const volpath::PencilRun r =
                volpath::simulate_pencil(cs.medium, {cs.grid.dr_cm, cs.grid.nr}, o);
            return from_profile(md.name, r.profile, 3, r.seconds, r.paths, r.events);
        }));
    }
    return rows;
}

/// A case's table and the ratios of the times to 1 % on r R(r).
void print_case(const std::vector<Row>& rows, int threads) {
    for (const Row& r : rows) {
        const bool separate = r.engine.find("hero") == std::string::npos;
        std::vector<double> rel_rd;
        for (size_t c = 0; c < r.rd.size(); ++c) rel_rd.push_back(r.rd_se[c] / r.rd[c]);
        char rd[64], pr[64];
        std::snprintf(rd, sizeof rd, "%.4f %.4f %.4f", r.rd[0], r.rd[1], r.rd[2]);
        std::snprintf(pr, sizeof pr, "%.2e %.2e %.2e", r.profile_rel_se[0], r.profile_rel_se[1],
                      r.profile_rel_se[2]);
        std::printf(
            "%-18s %9.3f %10.1f %10.1f %9.1f | %-29s | %-29s | %11.3g %11.3g\n", r.engine.c_str(),
            r.seconds, static_cast<double>(r.paths) / (r.seconds * 1e3),
            r.seconds * 1e9 * threads / static_cast<double>(std::max<std::uint64_t>(1, r.events)),
            static_cast<double>(r.events) / static_cast<double>(r.paths), rd, pr,
            time_to(r.seconds, rel_rd, separate, 0.01),
            time_to(r.seconds, r.profile_rel_se, separate, 0.01));
    }
    const double mc = time_to(rows[0].seconds, rows[0].profile_rel_se, true, 0.01);
    const double analog = time_to(rows[1].seconds, rows[1].profile_rel_se, true, 0.01);
    const double weighted = time_to(rows[2].seconds, rows[2].profile_rel_se, true, 0.01);
    const double hero = time_to(rows[3].seconds, rows[3].profile_rel_se, false, 0.01);
    const double hero_mfp = time_to(rows[4].seconds, rows[4].profile_rel_se, false, 0.01);
    const double hero_w = time_to(rows[5].seconds, rows[5].profile_rel_se, false, 0.01);
    std::printf(
        "time to 1 %% on r R(r) in all channels, ratios: hero / analog = %.2f, hero / "
        "weighted = %.2f, hero mfp / analog = %.2f, hero wtd / weighted = %.2f; volpath "
        "analog / MCML = %.2f, weighted / MCML = %.2f, hero / MCML = %.2f, hero mfp / MCML "
        "= %.2f, hero wtd / MCML = %.2f\n",
        hero / analog, hero / weighted, hero_mfp / analog, hero_w / weighted, analog / mc,
        weighted / mc, hero / mc, hero_mfp / mc, hero_w / mc);
}

/// The lit sphere (no MCML counterpart): Skin1, radius 5 mm, profile over beta only.
void bench_sphere(int threads, double q, int repeat) {
    const Medium skin1 = *find_material("Skin1");
    const std::int64_t photons = static_cast<std::int64_t>(200'000 * q);
    std::printf(
        "\nSkin1 sphere, radius 5 mm, directional light, exitance over beta (180 "
        "bins, no image): %lld photons per channel\n",
        static_cast<long long>(photons));
    std::printf("%-18s %9s %10s %10s %9s | %-29s | %11s %11s\n", "engine", "wall_s", "paths/ms",
                "ns/event", "events/p", "diffuse exit (R, G, B)", "t_1%_tot_s", "t_1%_M_s");
    const std::pair<volpath::ChromaticMode, const char*> modes[] = {
        {volpath::ChromaticMode::kPerChannel, "volpath analog"},
        {volpath::ChromaticMode::kHero, "volpath hero"}};
    for (const auto& [mode, name] : modes) {
        volpath::SphereScene sc;
        sc.medium = skin1;
        sc.radius_cm = 0.5;
        volpath::SphereOptions o;
        o.threads = threads;
        o.mode = mode;
        o.image = false;
        o.budget.samples = photons;
        volpath::SphereRun best;
        for (int k = 0; k < repeat; ++k) {
            volpath::SphereRun r = volpath::simulate_sphere(sc, o);
            if (k == 0 || r.seconds < best.seconds) best = std::move(r);
        }
        const bool separate = mode == volpath::ChromaticMode::kPerChannel;
        std::vector<double> rel_tot, rel_m;
        for (int c = 0; c < 3; ++c) {
            rel_tot.push_back(best.diffuse_se[c] / best.diffuse[c]);
            double num = 0, den = 0;
            for (size_t j = 0; j < best.exitance[c].size(); ++j) {
                num += best.exitance_se[c][j] * best.exitance_se[c][j];
                den += best.exitance[c][j] * best.exitance[c][j];
            }
            rel_m.push_back(den > 0 ? std::sqrt(num / den) : 0.0);
        }
        char dif[64];
        std::snprintf(dif, sizeof dif, "%.4f %.4f %.4f", best.diffuse[0], best.diffuse[1],
                      best.diffuse[2]);
        std::printf("%-18s %9.3f %10.1f %10.1f %9.1f | %-29s | %11.3g %11.3g\n", name, best.seconds,
                    static_cast<double>(best.paths) / (best.seconds * 1e3),
                    best.seconds * 1e9 * threads /
                        static_cast<double>(std::max<std::uint64_t>(1, best.events)),
                    static_cast<double>(best.events) / static_cast<double>(best.paths), dif,
                    time_to(best.seconds, rel_tot, separate, 0.01),
                    time_to(best.seconds, rel_m, separate, 0.01));
    }
}

}  // namespace

int run_volpath_bench(int threads, bool quick, int repeat) {
    const double q = quick ? 0.1 : 1.0;
    const std::vector<Case> cases = bench_cases(q);
    std::printf("volpath vs MCML default engine, %d thread%s (--threads), fastest of %d run%s\n",
                threads, threads == 1 ? "" : "s", repeat, repeat == 1 ? "" : "s");
    for (const Case& cs : cases) {
        std::printf("\n%s: %lld paths per channel\n", cs.name.c_str(),
                    static_cast<long long>(cs.photons));
        std::printf("%-18s %9s %10s %10s %9s | %-29s | %-29s | %11s %11s\n", "engine", "wall_s",
                    "paths/ms", "ns/event", "events/p", "Rd (R, G, B)",
                    "rel SE of r R(r) (R, G, B)", "t_1%_Rd_s", "t_1%_rR_s");
        print_case(case_rows(cs, threads, repeat), threads);
    }
    bench_sphere(threads, q, repeat);
    std::printf(
        "\npaths/ms counts one path per channel for the per-channel engines and one path for all "
        "three channels in hero mode. ns/event is CPU time per scattering event. t_1%% is the "
        "extrapolated wall time to 1 %% relative SE in every channel (per-channel engines: the "
        "three runs' times summed; hero: until the worst channel gets there).\n");
    return 0;
}

}  // namespace ssslab::cli
