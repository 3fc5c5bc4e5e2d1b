// The sphere study behind `ssslab sphere`: a homogeneous sphere under a directional light
// rendered by the light-tracing ground truth (volpath/sphere.h) and by analytic diffusion
// profiles integrated over the sphere (approx/sphere_bssrdf.h) [Bitterli13 §3.1.3, §3.5], side
// by side, with the error of every model against the path tracer.
//
// Geometry: the light and the camera directions are given as angles from +z in the x-z plane,
// l = (sin a_l, 0, cos a_l), v = (sin a_v, 0, cos a_v) (towards the light, towards the camera);
// the camera's up is volpath's default (+y). Lengths: the sphere radius in mm or cm; the
// coefficients and the radius are passed to both engines in cm.
//
// What the study produces (the command writes it, all or nothing, for the prefix <out>):
//   image        volpath's layers (exitance, subsurface, specular, radiance and their
//                "<layer>.stderr"), then "model.<name>" per model: M / pi per pixel [1/sr per
//                unit E0], the pixel average of the integrated exitance (volpath's "exitance")
//   preview      side by side from the left: volpath's exitance, then each model in the order
//                given, all at one exposure (the 99.5th percentile of volpath's exitance values
//                maps to 1)
//   beta_csv     per beta bin: edges [deg], per channel volpath's M and its standard error, its
//                single-scattering part M_ss and that one's standard error, each model's M and
//                z = (model - volpath) / SE (nan where SE = 0), where volpath means M for models
//                with single scattering and M - M_ss for those without
//   resolved_toml  the resolved configuration, per-channel totals and errors, timing, provenance
#pragma once

#include "approx/diffusion.h"
#include "approx/sphere_bssrdf.h"
#include "core/batch_runner.h"
#include "core/config.h"
#include "core/film_image.h"
#include "volpath/sphere.h"

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace ssslab::runner {

/// What a sphere study reads: the config file (empty: none) and the command line's values,
/// which override the config's (and are recorded in the resolved configuration).
struct SphereStudyInput {
    std::string config, material, models, mode, entry;
    std::optional<double> radius_mm, light_deg, camera_deg;
    std::optional<int> size;
    std::optional<std::uint64_t> seed;
    std::optional<std::int64_t> photons;
    std::optional<double> seconds, rel_error;
    std::int64_t batch = 0;
    int threads = 0;
};

struct SphereJob {
    std::string source;  ///< the config file, or "<command line>"
    std::shared_ptr<ConfigDocument> doc;
    volpath::SphereScene scene;
    std::uint64_t seed = 1;
    SampleBudget budget;
    std::int64_t batch = 0;
    std::string mode = "analog";
    double light_deg = 0, camera_deg = 60;
    std::vector<std::string> models;
    approx::SphereIntegration integration;
    int supersampling = 4;
    /// Per model, per channel: the profile (built at validation, so bad media fail early).
    std::vector<std::array<std::unique_ptr<approx::DiffusionProfile>, 3>> profiles;
};

/// The job of `in`, validated before any work (every model built for every channel): InputError
/// naming the file or option otherwise.
SphereJob read_sphere_job(const SphereStudyInput& in);

/// A model against volpath over the beta bins: relative L2 errors (zone-area weighted) over the
/// lit (bin centre < 90 deg) and unlit hemispheres, and chi-square over the bins with SE > 0.
struct SphereComparison {
    double rel_l2_lit = 0, rel_l2_unlit = 0, chi2 = 0;
    int dof = 0;
};

struct SphereStudy {
    std::vector<std::array<approx::SphereExitance, 3>> tables;  ///< per model, per channel
    double model_seconds = 0;
    volpath::SphereRun run;  ///< interrupted: nothing below is filled
    LayeredImage image{1, 1}, preview{1, 1};
    double exposure = 0;                               ///< of the preview, in stops
    std::vector<std::array<SphereComparison, 3>> cmp;  ///< per model, per channel
    std::string beta_csv, resolved_toml;
};

/// The analytic models first (seconds: their failures come before the long run), then the path
/// tracer with `so`'s run control (cancel, checkpoints, fresh, callbacks; seed, threads,
/// budget, batch and mode come from the job), then the outputs. `command_line` goes into the
/// provenance.
SphereStudy run_sphere_study(SphereJob& job, volpath::SphereOptions so,
                             const std::string& command_line);

}  // namespace ssslab::runner
