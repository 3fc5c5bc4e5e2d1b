#include "mcml/run_spec.h"

#include "core/error.h"
#include "core/material.h"

#include <cmath>
#include <limits>
#include <sstream>

namespace ssslab::mcml {

void compute_critical_angles(RunSpec& run) {
    auto& L = run.layers;
    const int N = run.num_layers();
    for (int i = 1; i <= N; ++i) {
        double n1 = L[i].n, n2 = L[i - 1].n;
        L[i].cos_crit0 = n1 > n2 ? std::sqrt(1.0 - n2 * n2 / (n1 * n1)) : 0.0;
        n2 = L[i + 1].n;
        L[i].cos_crit1 = n1 > n2 ? std::sqrt(1.0 - n2 * n2 / (n1 * n1)) : 0.0;
    }
}

double specular_reflectance(const std::vector<Layer>& L) {
    // MCML 1.2.2 Rspecular(), same operations in the same order.
    double temp = (L[0].n - L[1].n) / (L[0].n + L[1].n);
    double r1 = temp * temp;
    if (L[1].glass()) {  // L[2] exists: it is the ambient below when N = 1
        temp = (L[1].n - L[2].n) / (L[1].n + L[2].n);
        const double r2 = temp * temp;
        r1 = r1 + (1 - r1) * (1 - r1) * r2 / (1 - r1 * r2);
    }
    return r1;
}

RunSpec run_for_channel(const Medium& m, int c, std::int64_t photons, const Grid& grid) {
    RunSpec run;
    run.out_name = m.name + "_" + kChannelNames[c] + ".mco";
    run.photons = photons;
    run.grid = grid;
    const std::vector<MediumLayer> layers = m.layers();
    run.layers.resize(layers.size() + 2);
    run.layers[0].n = m.eta_above;
    double z = 0.0;
    for (size_t i = 0; i < layers.size(); ++i) {
        Layer& l = run.layers[i + 1];
        l.n = layers[i].eta;
        l.mua = layers[i].sigma_a_per_cm[c];
        l.mus = layers[i].sigma_s_per_cm[c];
        l.g = layers[i].g[c];
        l.z0 = z;
        z += layers[i].thickness_cm;
        l.z1 = z;
    }
    Layer& below = run.layers.back();
    below.n = m.eta_below;
    below.z0 = below.z1 = z;
    compute_critical_angles(run);
    return run;
}

double estimate_events_per_photon(const RunSpec& run) {
    const int N = run.num_layers();
    double albedo_max = 0.0, tau = 0.0, tau_tr = 0.0;
    bool scattering = false;
    for (int i = 1; i <= N; ++i) {
        const Layer& l = run.layers[i];
        if (l.glass()) continue;
        scattering = true;
        const double d = l.thickness_cm();
        tau += l.mus * d;
        tau_tr += l.mus * (1.0 - l.g) * d;
        if (l.mus > 0) albedo_max = std::max(albedo_max, l.mus / (l.mua + l.mus));
    }
    if (!scattering) return 1.0;
    // Absorption bound: weight falls below the roulette threshold 1e-4 after ln(1e-4)/ln(a)
    // events, and each roulette survival (p = 0.1) costs ln(10)/(-ln a) more.
    double n_abs = std::numeric_limits<double>::infinity();
    if (albedo_max < 1.0)
        n_abs = (std::log(1e4) + std::log(10.0) / 9.0) / -std::log(albedo_max) + 1.0;
    // Escape bound for a finite stack: a diffusive walk needs about tau'^2 transport steps of
    // 1/(1-g) events each to cross tau' transport mean free paths (tau events when g -> 1).
    const double n_esc = (1.0 + tau) * (1.0 + tau_tr);
    return std::min(n_abs, n_esc);
}

namespace {

std::string where(const RunSpec& run, int line) {
    if (run.source_file.empty()) return "";
    return run.source_file + ":" + std::to_string(line > 0 ? line : run.source_line) + ": ";
}

}  // namespace

void check_run(const RunSpec& run, bool compat) {
    const int N = run.num_layers();
    if (N < 1) throw InfeasibleError(where(run, 0) + "a run needs at least one layer");
    if (run.layers[1].glass() && N == 1)
        throw InfeasibleError(where(run, run.layers[1].source_line) +
                              "layer 1 is glass (mua = mus = 0) and is the only layer: MCML "
                              "starts photons in the layer below a glass first layer, and there "
                              "is none");
    bool any_scattering = false;
    for (int i = 1; i <= N; ++i) any_scattering |= !run.layers[i].glass();
    if (!any_scattering)
        throw InfeasibleError(where(run, run.layers[1].source_line) +
                              "every layer is glass (mua = mus = 0): nothing scatters or absorbs, "
                              "so there is nothing for MCML to simulate");
    for (int i = 1; i <= N; ++i) {
        const Layer& l = run.layers[i];
        if (l.glass() || l.mua > 0 || l.mus == 0) continue;
        const double tau_tr = l.mus * (1.0 - l.g) * l.thickness_cm();
        if (tau_tr > 1e4) {
            std::ostringstream os;
            os << where(run, l.source_line) << "layer " << i << " has mua = 0 and is "
               << l.thickness_cm() << " cm thick (" << tau_tr
               << " transport mean free paths): without absorption a photon random-walks "
                  "until it escapes, and in a (quasi-)infinite layer the expected number of "
                  "steps is unbounded. Give the layer a positive mua or a finite thickness.";
            throw InfeasibleError(os.str());
        }
    }
    const double events = estimate_events_per_photon(run);
    if (events > 1e9) {
        std::ostringstream os;
        os << where(run, run.layers[1].source_line) << "each photon would need about " << events
           << " scattering events (albedo too close to 1 for the layer thicknesses): that is "
              "over a minute per photon. Increase mua or reduce the thickness.";
        throw InfeasibleError(os.str());
    }
    const auto& g = run.grid;
    if (compat) {
        const int lim = 32767;  // the original stores grid sizes in a C short
        if (g.nz > lim || g.nr > lim || g.na > lim)
            throw InfeasibleError(where(run, 0) +
                                  "grid sizes above 32767 do not fit the original MCML's short "
                                  "integers; use the default mode for larger grids");
    }
    const double cells = static_cast<double>(g.nr) * (2.0 * g.na + g.nz);
    if (cells > 2e8) {
        std::ostringstream os;
        os << where(run, 0) << "the grid needs " << cells
           << " tally cells (nr x (2 na + nz)); more than 2e8 would not fit in memory. Use fewer "
              "bins.";
        throw InfeasibleError(os.str());
    }
}

}  // namespace ssslab::mcml
