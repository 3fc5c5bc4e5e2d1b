// [outputs.stiff]: the stiff sweep (issue 17). Every engine and model on the extremes of its
// inputs, each run checked for three things: no NaN or Inf in anything it produced, its energy
// where physics fixes it (within its standard error, or within a stated deterministic
// allowance), and that it ended (a run given `seconds_cap` that stops by the clock instead of by
// its budget has not ended).
//
//   [outputs.stiff]
//   photons = 20000       # per Monte Carlo run (MCML, the pencil, the lit sphere)
//   spp = 192             # per pixel of a furnace render (16 x 16; 96 at least: 32 batches of 3)
//   seconds_cap = 300     # per run
//   quick_factor = 0.1    # --quick multiplies photons and spp by this (at least 1000 and 96)
//   alpha = 0.01          # family-wise significance of the sweep's z-tests (Sidak)
//
// The media are grey (one set of coefficients in all channels): the base is sigma_s 9, sigma_a
// 1 per cm, g 0.8, eta 1.4 in air, 0.2 cm thick (a slab) or in radius (a sphere), and one
// parameter moves at a time:
//   albedo     1e-6, 1e-3, 0.5, 0.99, 1 - 1e-6, 1 - 1e-9 (sigma_t 10 per cm); and a half-space
//              (1e5 cm) at 1 - 1e-6
//   g          -0.999999, -0.99, 0, 0.99, 0.999999
//   eta        0.5, 0.8, 1, 1.33, 2, 2.5 (the medium's index over the ambient's)
//   scale      every length times 1e-7, 1e-3, 1e3, 1e5 (thickness, radius, mean free paths and
//              bins): the same problem, so the same numbers (compared with the base, both SEs)
//   thickness  1e-7, 1e-3, 1e5 cm at the base coefficients
//   kernel     widths from 1e-4 pixel to 1e4 images (the separable models and the SSS pass)
//
// What is checked, and against what (never against the code under test):
//   mcml       Rsp + Rd + A + Tt = 1 (conservation; the batch tally of Rd + A + Tt carries its
//              SE); at scale s, Rd and Tt equal the base's.
//   pencil     Rd and Tt equal MCML's (the independent engine), both SEs, plus the mass at
//              risk in the long-path roulette as a deterministic allowance.
//   sphere     the first-surface reflection equals its quadrature (sphere_specular_reflectance);
//              diffuse + specular <= 1, and = 1 up to the absorption bound (1 - albedo) x events
//              per photon (plus the mass at risk) when the albedo is 1 - 1e-6 or more.
//   render     a furnace: the sphere under a constant environment of radiance 1; the image mean
//              over the sphere's pixels <= 1, and = 1 up to (1 - albedo) x queries per path when
//              the albedo is 1 - 1e-6 or more (every scattering event costs at least a query).
//   diffusion  every analytic profile: R_d(r) finite and >= 0 on r from 1e-6 to 1e4 reduced mean
//              free paths; 0 <= R_dr <= 1; 2 pi int R_d r dr (adaptive quadrature) equals R_dr.
//   kernels    every separable model built from a dipole kernel at each width: a constant image
//              convolved (full-resolution separable passes, approx/convolve.h) stays equal to the
//              kernel's mass; the SSS pass on a constant G-buffer gives its taps' mass; the
//              taps' mass equals the kernel's.
// A model that refuses an input (std::invalid_argument, InfeasibleError) is listed as refused
// with its message: a clear refusal is not a failure; a crash, a hang or a NaN is.
//
// results/<name>/stiff/sweep.csv: one row per check (engine, axis, value, quantity, test,
// estimate, SE, expected, its SE, an interval's upper end, the deterministic allowance, z, the
// counts of non-finite and out-of-range values, seconds, ended, refused, pass, note) and
// summary.csv (per engine and axis: checks, passed, refused, non-finite, worst |z|, longest run).
// Metrics: per engine the number of failed checks (deterministic, must stay 0).
#pragma once

#include "core/config.h"
#include "experiments/runner/scene_renders.h"
#include "experiments/runner/study.h"

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace ssslab::runner {

struct StiffStudySpec {
    bool enabled = false;
    std::int64_t photons = 20000;
    std::int64_t spp = 192;
    double seconds_cap = 300;
    double quick_factor = 0.1;
    double alpha = 0.01;
};

/// Parse [outputs.stiff].
StiffStudySpec read_stiff_study(ConfigTable& t);

// A study plugin (experiments/runner/study.h): [outputs.stiff] registers read_stiff_study, whose
// study runs run_stiff_study: files stiff/sweep.csv and stiff/summary.csv, metrics
// stiff.<family>.failed, and the report's section.
StudyResult run_stiff_study(const StiffStudySpec& spec, const RenderStudyContext& ctx);

}  // namespace ssslab::runner
