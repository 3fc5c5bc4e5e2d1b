// Experiment configs (TOML, under experiments/<group>/): what to compute and what to show.
//
//   [experiment]      name (results/<name>/), title, description, seed
//   [materials]       presets = [...] (Freude14 Table 6.2) and/or [[materials.custom]] tables
//                     (a name plus the keys of a material: sigma_a_per_mm, ..., see
//                     core/material.h)
//   [mcml]            the ground-truth engine's budget per RGB channel: photons, seconds or
//                     rel_error; quick_factor (what --quick multiplies budgets by); batch_photons;
//                     [mcml.grid] dr_mm / dr_cm and nr (default: Freude14 Table 6.1)
//   [volpath]         the second engine (volumetric path tracer), run per material and channel
//                     beside MCML when an output needs it: photons, seconds or rel_error per
//                     channel; mode = "analog" | "weighted"; quick_factor; batch_paths
//   [outputs.profiles]       CSV of R_d(r) per material and a summary table (unit = "mm"|"cm")
//   [outputs.profile_plots]  linear plot near zero, log plot, r R(r) (linear_range_mfp)
//   [outputs.convergence]    error against run time for `materials`, against an independent
//                            reference run with reference_factor times the budget
//   [outputs.crossval]       MCML against volpath bin by bin: per-bin z-scores, chi-square per
//                            material and channel, the z histogram (needs [volpath])
//   [outputs.pencil]         pencil-beam plots [Bitterli13 §3.6.3]: analytic diffusion models
//                            (models = [...], approx/diffusion.h) against both engines, and a
//                            table of each model's error (needs [volpath])
//   [outputs.efficiency]     error against run time of both engines on the same problem
//                            (materials = [...]; needs [volpath])
//   [[outputs.kernels]]      kernel studies: separable models scored in kernel and image space
//                            (experiments/runner/kernel_study.h)
//   [outputs.render]         ground-truth images of scene files with rays/s and time to 1 %
//                            (a plugin: experiments/runner/studies/render/); needs no [materials]
//   [outputs.realtime]       the real-time renderer's frames of scene files scored against the
//                            screen-space reference and the path tracer, Freude14 Table 6.4
//                            (a plugin: experiments/runner/studies/realtime/); needs no
//                            [materials]
//   [outputs.stiff]          the stiff sweep: every engine and model on the extremes of its
//                            inputs (a plugin: experiments/runner/studies/stiff/); needs no
//                            [materials]
//   [outputs.<name>]         a plugin study of experiments/runner/studies/<name>/
//                            (experiments/runner/study.h); needs no [materials]
// Every error names file:line:column and the key.
#pragma once

#include "core/batch_runner.h"
#include "core/config.h"
#include "core/material.h"
#include "core/profile.h"
#include "experiments/runner/kernel_study.h"
#include "experiments/runner/profile_models.h"
#include "experiments/runner/scene_renders.h"
#include "mcml/engine.h"
#include "mcml/profile.h"

#include <array>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace ssslab::runner {

struct MaterialEntry {
    std::string label;  ///< name in tables and file names
    Medium medium;
};

struct McmlSetup {
    SampleBudget budget;         ///< per RGB channel, before --quick
    double quick_factor = 0.02;  ///< --quick multiplies photon and time budgets by this
    std::int64_t batch_photons = 0;
    mcml::GridOverride grid;  ///< over Freude14 Table 6.1
};

struct VolpathSetup {
    bool enabled = false;
    SampleBudget budget;  ///< per RGB channel, before --quick
    double quick_factor = 0.02;
    std::int64_t batch_paths = 0;
    std::string mode = "analog";  ///< "analog" | "weighted" (volpath::Absorption)
};

struct Experiment {
    std::string source;  ///< config file (or "<built-in>")
    std::string name, title, description;
    std::uint64_t seed = 1;
    std::vector<MaterialEntry> materials;
    McmlSetup mcml;

    struct Profiles {
        bool enabled = false;
        LengthUnit unit = LengthUnit::kMm;
    } profiles;
    struct ProfilePlots {
        bool enabled = false;
        double linear_range_mfp = 2.0;  ///< the linear panel spans at most this many (largest)
                                        ///< MFPs (plot.py zooms to where the profile falls)
    } profile_plots;
    struct Convergence {
        bool enabled = false;
        std::vector<std::string> materials;  ///< labels
        double reference_factor = 4.0;
    } convergence;

    VolpathSetup volpath;
    struct CrossVal {
        bool enabled = false;
        /// Bins enter the chi-square when both estimates have a relative SE below this (so
        /// Gaussian statistics apply).
        double max_rel_se = 0.3;
    } crossval;
    struct Pencil {
        bool enabled = false;
        /// The models (`models`: built-in names and profile files, relative to the config) and
        /// their parameters ([outputs.pencil.parameters]): experiments/runner/profile_models.h.
        ProfileModels models;
    } pencil;
    struct Efficiency {
        bool enabled = false;
        std::vector<std::string> materials;
    } efficiency;

    std::vector<KernelStudySpec> kernel_studies;  ///< [[outputs.kernels]]
    /// The plugin studies (experiments/runner/study.h) this config has an [outputs.<name>] of,
    /// in the registry's order.
    struct PluginStudy {
        std::string name;
        std::shared_ptr<const class Study> study;
    };
    std::vector<PluginStudy> studies;

    std::shared_ptr<ConfigDocument> doc;  ///< parsed config; holds the resolved configuration
};

/// Parse and validate an experiment config. Throws InputError.
Experiment read_experiment(const std::string& path);
Experiment parse_experiment(std::string_view text, const std::string& name);

/// The built-in default experiment (experiments/freude14/profiles.toml, embedded at build time).
std::string_view default_experiment_toml();

}  // namespace ssslab::runner
