// The description of one MCML run: layers, ambient media, grid and photon count, as in the
// InputStruct of MCML 1.2.2 (Wang, Jacques & Zheng 1995). Lengths in cm, coefficients in 1/cm.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace ssslab {
struct Medium;
}

namespace ssslab::mcml {

/// A layer (or an ambient medium, for indices 0 and N+1). Units: cm and 1/cm.
struct Layer {
    double z0 = 0, z1 = 0;  ///< top and bottom z [cm]
    double n = 1;           ///< refractive index
    double mua = 0;         ///< absorption coefficient [1/cm]
    double mus = 0;         ///< scattering coefficient [1/cm]
    double g = 0;           ///< Henyey-Greenstein anisotropy
    double cos_crit0 = 0;   ///< cosine of the critical angle at the top boundary (0: none)
    double cos_crit1 = 0;   ///< cosine of the critical angle at the bottom boundary (0: none)
    int source_line = 0;    ///< line of the .mci (or config) it came from, for messages

    /// MCML treats a layer with mua = mus = 0 as glass: no interaction, straight flight.
    bool glass() const { return mua == 0.0 && mus == 0.0; }
    double thickness_cm() const { return z1 - z0; }
};

/// Grid of the tallies. dz, dr in cm; da = pi / (2 na) rad.
struct Grid {
    double dz = 0, dr = 0;
    int nz = 0, nr = 0, na = 0;
};

/// One independent run.
struct RunSpec {
    std::string out_name;   ///< output file name as written in the .mci
    char out_format = 'A';  ///< 'A' (ASCII) or 'B' (the original writes text for both)
    std::int64_t photons = 0;
    Grid grid;
    /// layers[0] is the ambient medium above, layers[1..N] the slab layers, layers[N+1] the
    /// ambient medium below (only n is used for the ambient media), as MCML's layerspecs.
    std::vector<Layer> layers;

    std::string source_file;  ///< .mci it came from (empty if built in code)
    int source_line = 0;      ///< line of its output-name entry

    int num_layers() const { return static_cast<int>(layers.size()) - 2; }
};

/// Set the critical-angle cosines of layers 1..N from the indices, as MCML's CriticalAngle().
void compute_critical_angles(RunSpec& run);

/// Specular reflectance at entry: Fresnel at normal incidence from the top ambient into layer 1;
/// if layer 1 is glass, the multiple reflections inside it are included (MCML's Rspecular()).
double specular_reflectance(const std::vector<Layer>& layers);

/// Build a single-layer run for one RGB channel of a medium (MCML set-up of Freude14 §6.1).
RunSpec run_for_channel(const Medium& m, int channel, std::int64_t photons, const Grid& grid);

/// Validation beyond what the .mci parser can see. Throws InfeasibleError when the run cannot
/// terminate in bounded expected time (e.g. mu_a = 0 in a quasi-infinite scattering layer) or
/// would need an unreasonable amount of memory; the message says why and what to change.
/// `compat` applies the original's limits (grid sizes fit in a C short, g >= 0).
void check_run(const RunSpec& run, bool compat);

/// A rough upper estimate of the scattering events per photon (for the feasibility check and
/// for choosing a default batch size).
double estimate_events_per_photon(const RunSpec& run);

}  // namespace ssslab::mcml
