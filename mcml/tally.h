// Tallies of an MCML run: raw photon weights as the transport deposits them, their 1D and 0D
// reductions, and the scaled physical quantities of the .mco file.
//
// A tally is one flat vector so that a batch of photons can be folded into a BatchAccumulator
// element by element: every quantity, the 2D arrays, their 1D reductions and the totals, gets its
// own standard error. Two layouts exist:
//   full    -- the original's arrays: A_rz, Rd_ra, Tt_ra, reduced to A_z, A_l, Rd_r, Rd_a, Tt_r,
//              Tt_a and the totals; photons outside the grid go into the last bins as in MCML.
//   profile -- only what a radial reflectance profile needs: Rd_r and Tt_r with an extra overflow
//              bin for photons beyond the grid (so the last bin is not polluted), absorption per
//              layer, and the totals. No angle or depth bins, no acos per exiting photon.
#pragma once

#include "mcml/run_spec.h"

#include <cstdint>
#include <vector>

namespace ssslab::mcml {

enum class TallyMode { kFull, kProfile };

/// Offsets of each quantity in a flat tally vector.
struct TallyLayout {
    TallyMode mode = TallyMode::kFull;
    int nr = 0, nz = 0, na = 0, nl = 0;  // nl: number of layers (arrays over layers have nl + 2)
    // Primary (deposited by the transport).
    size_t rd_ra = 0, tt_ra = 0, a_rz = 0;   // full: nr*na, nr*na, nr*nz (row-major by r)
    size_t rd_r = 0, tt_r = 0, a_layer = 0;  // profile: nr+1, nr+1, nl+2 (primary)
    // Derived (full mode: computed by reduce() as MCML's Sum2D*; profile mode: totals only).
    size_t rd_a = 0, tt_a = 0, a_z = 0, a_l = 0;
    size_t rd = 0, a = 0, tt = 0, energy = 0;  // totals; energy = Rd + A + Tt of the batch
    size_t primary_size = 0, size = 0;

    static TallyLayout make(const RunSpec& run, TallyMode mode);
};

/// Raw weights of some photons.
struct RawTally {
    const TallyLayout* layout = nullptr;
    std::vector<double> v;
    std::uint64_t events = 0;  ///< scattering events (for ns/event figures)

    explicit RawTally(const TallyLayout& l) : layout(&l), v(l.size, 0.0) {}
    void clear() {
        std::fill(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(layout->primary_size), 0.0);
        events = 0;
    }
};

/// Fill the derived sections of `t` from its primary sections (MCML's Sum2DRd, Sum2DA, Sum2DTt,
/// with the same loops in the same order). `run` supplies dz and the layer boundaries for A_l.
void reduce(const RunSpec& run, double* t, const TallyLayout& layout);

/// The scaled physical quantities of a run (MCML's OutStruct after SumScaleResult()).
struct McoResult {
    double rsp = 0, rd = 0, a = 0, tt = 0;
    std::vector<double> a_l;           ///< [1..nl] used, size nl + 2 [-]
    std::vector<double> a_z;           ///< [1/cm]
    std::vector<double> rd_r, tt_r;    ///< [1/cm^2]
    std::vector<double> rd_a, tt_a;    ///< [1/sr]
    std::vector<double> a_rz;          ///< nr x nz [1/cm^3]
    std::vector<double> rd_ra, tt_ra;  ///< nr x na [1/(cm^2 sr)]
};

/// Scale a reduced full-layout tally to physical units (MCML's ScaleRdTt() and ScaleA(), same
/// operations in the same order). `photons` is the divisor: the photon count for raw sums, 1 for
/// per-photon means or standard errors. `pi` is 3.1415926 in compatibility mode (MCML's PI) and
/// the exact value otherwise.
McoResult scale_full(const RunSpec& run, const std::vector<double>& t, const TallyLayout& layout,
                     double photons, double pi, double rsp);

}  // namespace ssslab::mcml
