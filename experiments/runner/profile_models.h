// The radial profile models a study names (issue 19), in one place: the built-in models
// (approx::make_diffusion_profile) and profile files, which a researcher writes without a
// rebuild: expressions in TOML (approx/expression_profile.h, on the CPU) and BSSRDF Explorer's
// .bssrdf files [Bitterli13 §A.2] (approx/bssrdf_file.h, their GLSL run through the GL twin:
// realtime/gl/bssrdf_gl.h). A file is named by its path (ending in .toml or .bssrdf, relative to
// the config that names it) and the model takes its file name ("dipole.toml"). Its parameters
// are set per RGB channel from a table of the config (read_parameters). The pencil study and
// `ssslab sphere` resolve their model lists here.
#pragma once

#include "approx/bssrdf_file.h"
#include "approx/diffusion.h"
#include "approx/expression_profile.h"
#include "core/config.h"
#include "core/hash.h"

#include <array>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace ssslab::runner {

class ProfileModels {
  public:
    /// Whether `entry` names a profile file (ends in .toml or .bssrdf).
    static bool is_file_entry(const std::string& entry);

    /// Adds the model `entry` names: a built-in name, or a profile file's path relative to
    /// `base_dir`, read and checked now (a .bssrdf file's GLSL compiled). Returns the model's
    /// name. Throws std::invalid_argument (the caller locates it at its key) for an unknown name,
    /// a file that is not there, a name given twice, a .bssrdf file in a build without the GL
    /// twin or where no GL context can be made; InputError at the file's own line for a bad file.
    std::string add(const std::string& entry, const std::string& base_dir);

    /// The models' names in the order added.
    const std::vector<std::string>& names() const { return names_; }

    /// Reads `t` (e.g. [outputs.pencil.parameters]): a sub-table per file model, named by the
    /// model's name, of its parameters, each in its declared range (a float one number or one per
    /// RGB channel, a bool true or false, a color its RGB). A table of a built-in model is refused
    /// at its key; unknown keys are left to the config's finish() (with "did you mean").
    void read_parameters(ConfigTable& t);

    /// Sets parameter `param` of file model `model` (per RGB channel; a bool's 0 or 1, a color's
    /// RGB). Throws std::invalid_argument for a model that is not a file model of this set, a
    /// parameter it does not declare, or a float outside the parameter's range.
    void set_parameter(const std::string& model, const std::string& param,
                       const std::array<double, 3>& value);

    /// The model `name` for channel `c` of medium `m`. Throws std::invalid_argument where the
    /// model refuses the medium, std::runtime_error where a .bssrdf file cannot be evaluated.
    std::unique_ptr<approx::DiffusionProfile> make(const std::string& name,
                                                   const approx::DiffusionMedium& m, int c) const;

    /// What determines the models' results: names, the files' content, the parameter values.
    void add_to_key(ContentKey& k) const;

  private:
    std::vector<std::string> names_;
    std::map<std::string, approx::ExpressionProfileDef> expressions_;
    std::map<std::string, approx::BssrdfFile> bssrdfs_;
    /// Per file model, its parameters' values by name per RGB channel (a color: its RGB).
    std::map<std::string, std::map<std::string, std::array<double, 3>>> parameters_;
};

}  // namespace ssslab::runner
