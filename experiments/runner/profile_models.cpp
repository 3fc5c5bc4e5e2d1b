#include "experiments/runner/profile_models.h"

#include "core/build_info.h"
#include "core/error.h"
#if SSSLAB_HAVE_GL
#include "realtime/gl/bssrdf_gl.h"
#endif

#include <algorithm>
#include <filesystem>
#include <limits>
#include <stdexcept>

namespace ssslab::runner {

bool ProfileModels::is_file_entry(const std::string& entry) {
    return entry.ends_with(".toml") || entry.ends_with(".bssrdf");
}

std::string ProfileModels::add(const std::string& entry, const std::string& base_dir) {
    std::string name = entry;
    if (is_file_entry(entry)) {
        const std::filesystem::path file = std::filesystem::path(base_dir) / entry;
        if (!std::filesystem::is_regular_file(file))
            throw std::invalid_argument("no profile file " + file.string());
        name = file.filename().string();
        if (std::find(names_.begin(), names_.end(), name) != names_.end())
            throw std::invalid_argument("two models named \"" + name + "\"");
        if (entry.ends_with(".toml")) {
            expressions_.emplace(name, approx::read_expression_profile(file.string()));
        } else {
            if (!SSSLAB_HAVE_GL)
                throw std::invalid_argument(
                    "a .bssrdf model needs the GL twin, which this build lacks (SSSLAB_WITH_GL; "
                    "apt-get install libosmesa6-dev libegl-dev python3-glad); a .toml profile "
                    "file needs none");
            approx::BssrdfFile f = approx::read_bssrdf(file.string());
#if SSSLAB_HAVE_GL
            // Compiled now, so that GLSL that does not compile is refused with the config.
            try {
                realtime::gl::check_bssrdf(f);
            } catch (const InputError&) {
                throw;
            } catch (const std::exception& x) {
                throw std::invalid_argument(
                    std::string("no OpenGL context to evaluate a .bssrdf model: ") + x.what());
            }
#endif
            bssrdfs_.emplace(name, std::move(f));
        }
    } else {
        const auto& known = approx::diffusion_model_names();
        if (std::find(known.begin(), known.end(), name) == known.end()) {
            std::string list;
            for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
            throw std::invalid_argument("unknown diffusion model \"" + name + "\"; known: " + list +
                                        ", or a profile file (a path ending in .toml or .bssrdf)");
        }
        if (std::find(names_.begin(), names_.end(), name) != names_.end())
            throw std::invalid_argument("model \"" + name + "\" given twice");
    }
    names_.push_back(name);
    return name;
}

void ProfileModels::read_parameters(ConfigTable& t) {
    // The config's reads check the ranges where a bad value is located (its item's column);
    // set_parameter checks them again for every other caller.
    for (const std::string& name : names_) {
        auto mt = t.table(name);
        if (!mt) continue;
        if (const auto f = expressions_.find(name); f != expressions_.end()) {
            for (const auto& p : f->second.parameters)
                if (auto v = mt->optional_rgb(p.name, Range::closed(p.min, p.max)))
                    set_parameter(name, p.name, *v);
        } else if (const auto b = bssrdfs_.find(name); b != bssrdfs_.end()) {
            for (const auto& p : b->second.parameters) {
                if (!mt->has(p.name)) continue;
                if (p.type == approx::BssrdfParameter::Type::kBool) {
                    const double v = mt->boolean(p.name, false) ? 1 : 0;
                    set_parameter(name, p.name, {v, v, v});
                } else if (p.type == approx::BssrdfParameter::Type::kFloat) {
                    set_parameter(name, p.name, mt->rgb(p.name, Range::closed(p.min, p.max)));
                } else {
                    set_parameter(name, p.name, mt->rgb(p.name));
                }
            }
        } else {
            t.fail(name,
                   "\"" + name + "\" is a built-in model: only profile files have parameters");
        }
    }
}

void ProfileModels::set_parameter(const std::string& model, const std::string& param,
                                  const std::array<double, 3>& value) {
    double lo = -std::numeric_limits<double>::infinity(), hi = -lo;
    bool known = false;
    if (const auto f = expressions_.find(model); f != expressions_.end()) {
        for (const auto& p : f->second.parameters)
            if (p.name == param) {
                known = true;
                lo = p.min;
                hi = p.max;
            }
    } else if (const auto b = bssrdfs_.find(model); b != bssrdfs_.end()) {
        if (const approx::BssrdfParameter* p = b->second.find_parameter(param)) {
            known = true;
            if (p->type == approx::BssrdfParameter::Type::kFloat) {
                lo = p->min;
                hi = p->max;
            }
        }
    } else {
        throw std::invalid_argument("\"" + model +
                                    "\" is not a profile file's model: only those have parameters");
    }
    if (!known)
        throw std::invalid_argument("model \"" + model + "\" has no parameter \"" + param + "\"");
    for (const double v : value)
        if (!(v >= lo && v <= hi))
            throw std::invalid_argument("parameter \"" + param + "\" of \"" + model +
                                        "\" = " + std::to_string(v) + " lies outside [" +
                                        std::to_string(lo) + ", " + std::to_string(hi) + "]");
    parameters_[model][param] = value;
}

std::unique_ptr<approx::DiffusionProfile> ProfileModels::make(const std::string& name,
                                                              const approx::DiffusionMedium& m,
                                                              int c) const {
    const auto given = parameters_.find(name);
    if (const auto f = expressions_.find(name); f != expressions_.end()) {
        std::map<std::string, double> v;  // each parameter's channel value
        if (given != parameters_.end())
            for (const auto& [key, rgb] : given->second) v[key] = rgb[static_cast<size_t>(c)];
        return approx::make_expression_profile(f->second, m, v);
    }
#if SSSLAB_HAVE_GL
    if (const auto f = bssrdfs_.find(name); f != bssrdfs_.end()) {
        // A float's channel value; a bool's, a color's as given (the result's component of the
        // channel is taken: realtime/gl/bssrdf_gl.h).
        realtime::gl::BssrdfParameterValues v;
        if (given != parameters_.end())
            for (const auto& [key, rgb] : given->second) {
                const approx::BssrdfParameter* d = f->second.find_parameter(key);
                v[key] = d && d->type == approx::BssrdfParameter::Type::kFloat
                             ? std::array<double, 3>{rgb[static_cast<size_t>(c)], 0, 0}
                             : rgb;
            }
        return realtime::gl::make_bssrdf_profile(f->second, name, m, c, v);
    }
#endif
    return approx::make_diffusion_profile(name, m);
}

void ProfileModels::add_to_key(ContentKey& k) const {
    for (const auto& n : names_) k.add("model", n);
    for (const auto& [name, def] : expressions_) k.add("model_file:" + name, def.text);
    for (const auto& [name, f] : bssrdfs_) k.add("model_file:" + name, f.text);
    for (const auto& [name, values] : parameters_)
        for (const auto& [param, v] : values) k.add("model_parameter:" + name + ":" + param, v);
}

}  // namespace ssslab::runner
