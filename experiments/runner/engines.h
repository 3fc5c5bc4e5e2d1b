// The outputs that put the two ground-truth engines side by side, and the analytic diffusion
// profiles against both [Bitterli13 §3.2, §3.6.3]:
//
//   crossval/    MCML against volpath bin by bin: per-bin z-scores, chi-square per material and
//                channel (summary.csv, z_scores.csv)
//   pencil/      per material the radial profiles of both engines and of every analytic model on
//                a common set of display bins (<material>.csv), and each model's error against
//                the path tracer (errors.csv), like with like: a model without single scattering
//                is compared with the multiple-scattering part, and a model without the entry
//                Fresnel factor is multiplied by 1 - Rsp (MCML's and volpath's R_d carry it)
//   efficiency/  progressive estimates of both engines against wall time (<material>.csv)
#pragma once

#include "experiments/runner/nodes.h"
#include "experiments/runner/plots.h"

#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace ssslab::runner {

/// The tables of [outputs.crossval], [outputs.pencil] and [outputs.efficiency], as file name
/// (relative to results/<name>/) -> content, and their metrics for `ssslab check` appended to
/// `metrics`: the path tracer's total diffuse reflectance and its single-scattering part per
/// material and channel (stochastic), each model's total (deterministic, analytic) and its
/// relative L2 error of r R(r) against the path tracer (stochastic: its standard error is what
/// the reference's noise gives it). Needs executed nodes.
std::map<std::string, std::string> engine_tables(const ExperimentRun& r,
                                                 std::vector<Metric>& metrics);

/// The plots of these outputs (plots.h PlotRequest).
std::vector<PlotRequest> engine_plots(const ExperimentRun& r);

/// The report sections of these outputs (tables from `files`, figures from `plots`).
void engine_report(const ExperimentRun& r, const std::map<std::string, std::string>& files,
                   const PlotResult& plots, std::ostringstream& os);

}  // namespace ssslab::runner
