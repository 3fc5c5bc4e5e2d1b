// Kernel studies: the separable models of approx/ built from an experiment's ground-truth
// profiles and scored in kernel space and in image space [Freude14 ch. 5-6].
//
// In a config, [[outputs.kernels]] tables:
//   name           the study's directory under results/<experiment>/kernels/
//   materials      labels of the experiment's materials (default: all)
//   models         model specs (approx/model_spec.h), e.g. ["svd:rank=1", "preintegration"]
//   signals        image-space test signals: edge, circle_squares, dot, skin_shaded, skin_uniform
//   taps           importance-sampled taps per 1D pass (odd, default 17; 0: none)
//   jitter         stratified jitter of the taps (0..1, default 0: none)
//   pixels         image size (default 256)
//   fov_mm         image width in mm (default: 8 times the radius holding 90 % of the widest
//                  channel's pre-integrated kernel)
//   refine         kernel grid refinement over the thesis grid (default 1)
//   images         PNG panels of the signals (default false)
//   kernel_plots   slices along the axis and the diagonal, as Freude14 Fig. 6.2 (default false)
//   singular_values  the leading singular values per channel, 0 for none (Fig. 5.1)
//   compare        "freude14_table_6_3" prints Table 6.3's normalised numbers beside ours
//   reference      one of the models: every model's image is also compared with this model's
//                  (e.g. how close guided optimization comes to pre-integration, Fig. 5.15)
#pragma once

#include "approx/image.h"
#include "approx/model_spec.h"
#include "core/config.h"
#include "core/profile.h"

#include <map>
#include <string>
#include <vector>

namespace ssslab::runner {

struct KernelStudySpec {
    std::string name;
    std::vector<std::string> materials;
    std::vector<approx::ModelSpec> models;
    std::vector<approx::Signal> signals;
    int taps = 17;
    double jitter = 0;
    int pixels = 256;
    double fov_mm = 0;
    int refine = 1;
    bool images = false;
    bool kernel_plots = false;
    int singular_values = 0;
    std::string compare;
    std::string reference;  ///< a model's spec text, or empty

    /// Canonical text of everything that determines the study's results (for its cache key).
    std::string canonical() const;
};

/// Read one [[outputs.kernels]] table; `labels` are the experiment's material labels.
KernelStudySpec read_kernel_study(ConfigTable& t, const std::vector<std::string>& labels);

/// Version of the kernel-study code's numbers (part of the cache key).
const char* kernel_study_version();

/// Run a study on the materials' profiles. Returns its files, relative to the study directory
/// (CSV tables, PNG images), and a short text summary for the log.
std::map<std::string, std::string> run_kernel_study(
    const KernelStudySpec& spec, const std::map<std::string, RadialProfile>& profiles,
    std::string& summary);

}  // namespace ssslab::runner
