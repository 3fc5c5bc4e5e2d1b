// `ssslab materials`: the measured materials and the MCML grid they get.
#include "core/material.h"
#include "experiments/cli/commands.h"
#include "mcml/profile.h"

#include <cstdio>

namespace ssslab::cli {

void register_materials(CLI::App& app, std::function<int()>& action) {
    CLI::App* sub = app.add_subcommand(
        "materials", "List the measured materials of Freude14 Table 6.2 (coefficients in 1/cm)");
    sub->callback([&action] {
        action = [] {
            std::printf("%-10s %-22s %-22s %4s  %-26s %s\n", "name", "sigma_a [1/cm] RGB",
                        "sigma_s [1/cm] RGB", "eta", "albedo RGB", "grid dr [mm] x nr");
            for (const auto& p : freude14_materials()) {
                const Medium& m = p.medium;
                char sa[64], ss[64], al[64];
                std::snprintf(sa, sizeof sa, "%g %g %g", m.sigma_a_per_cm[0], m.sigma_a_per_cm[1],
                              m.sigma_a_per_cm[2]);
                std::snprintf(ss, sizeof ss, "%g %g %g", m.sigma_s_per_cm[0], m.sigma_s_per_cm[1],
                              m.sigma_s_per_cm[2]);
                std::snprintf(al, sizeof al, "%.6f %.6f %.6f", m.albedo(0), m.albedo(1),
                              m.albedo(2));
                const auto g = mcml::freude14_grid(m);
                std::printf("%-10s %-22s %-22s %4g  %-26s %.4g x %d\n", p.name, sa, ss, m.eta, al,
                            g.dr_cm * 10.0, g.nr);
            }
            std::printf("Source: %s. g = 0, thickness 1e8 cm (quasi-infinite).\n",
                        freude14_materials().front().source);
            return 0;
        };
    });
}

}  // namespace ssslab::cli
