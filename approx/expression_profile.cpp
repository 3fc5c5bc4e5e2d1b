#include "approx/expression_profile.h"

#include "approx/bssrdf_file.h"
#include "approx/diffusion_detail.h"
#include "core/atomic_file.h"
#include "core/config.h"
#include "core/error.h"

#include <muParser.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <mutex>
#include <stdexcept>

namespace ssslab::approx {

namespace {

using diffusion_detail::kPi;

// The medium's names, in the order the error messages list them.
const std::vector<std::string>& medium_names() {
    static const std::vector<std::string> n = {"sigma_a",   "sigma_s",   "g",      "eta",
                                               "sigma_s_r", "sigma_t_r", "alpha_r"};
    return n;
}

bool reserved(const std::string& s) {
    const auto& m = medium_names();
    return s == "r" || s == "pi" || std::find(m.begin(), m.end(), s) != m.end();
}

std::string trim(const std::string& s) {
    const auto b = s.find_first_not_of(" \t");
    if (b == std::string::npos) return "";
    return s.substr(b, s.find_last_not_of(" \t") - b + 1);
}

// The variables an evaluation sees: the medium's, r, the parameters and the init names, at
// stable addresses (std::map nodes do not move) for muparser's DefineVar.
class Variables {
  public:
    double& operator[](const std::string& name) { return v_[name]; }
    bool has(const std::string& name) const { return v_.count(name) != 0; }
    void define_all(mu::Parser& p) {
        p.DefineConst("pi", kPi);
        // Beside muparser's own functions: e^x - 1 without cancellation near 0 (for profiles
        // that subtract close exponentials, as the better dipole's fluence).
        p.DefineFun(
            "expm1", +[](double x) { return std::expm1(x); });
        for (auto& [name, value] : v_) p.DefineVar(name, &value);
    }
    std::vector<std::string> names() const {
        std::vector<std::string> n = {"pi"};
        for (const auto& [name, value] : v_) n.push_back(name);
        return n;
    }
    std::string known() const {
        std::string k;
        for (const std::string& n : names()) k += (k.empty() ? "" : ", ") + n;
        return k;
    }
    /// The value of `expression` with these variables (muparser compiles it on the way).
    double evaluate(const std::string& expression) {
        mu::Parser p;
        define_all(p);
        p.SetExpr(expression);
        return p.Eval();
    }

  private:
    std::map<std::string, double> v_;
};

// muparser's message for an expression, with "unknown name" for an undefined identifier.
std::string parser_message(const mu::Parser::exception_type& e, const Variables& vars) {
    const std::string token = e.GetToken();
    if (e.GetCode() == mu::ecUNASSIGNABLE_TOKEN && is_glsl_identifier(token)) {
        const std::string near = nearest_name(token, vars.names(), suggestion_distance(token));
        return "unknown name '" + token + "' at position " + std::to_string(e.GetPos() + 1) +
               (near.empty() ? "" : " (did you mean '" + near + "'?)") +
               "; known here: " + vars.known();
    }
    return e.GetMsg();
}

void set_medium(Variables& v, const DiffusionMedium& m) {
    v["sigma_a"] = m.sigma_a;
    v["sigma_s"] = m.sigma_s;
    v["g"] = m.g;
    v["eta"] = m.eta;
    v["sigma_s_r"] = m.sigma_s_reduced();
    v["sigma_t_r"] = m.sigma_t_reduced();
    v["alpha_r"] = m.reduced_albedo();
}

class ExpressionProfile final : public DiffusionProfile {
  public:
    ExpressionProfile(const ExpressionProfileDef& def, const DiffusionMedium& m,
                      const std::map<std::string, double>& values)
        : DiffusionProfile(m), def_(def) {
        validate(m, FresnelMoments::fit);
        for (const auto& given : values) {
            const std::string& name = given.first;
            const double value = given.second;
            const auto p = std::find_if(def.parameters.begin(), def.parameters.end(),
                                        [&](const auto& q) { return q.name == name; });
            if (p == def.parameters.end())
                throw std::invalid_argument(def.path + ": the model has no parameter '" + name +
                                            "'");
            if (!(value >= p->min && value <= p->max))
                throw std::invalid_argument(
                    def.path + ": parameter '" + name + "' = " + std::to_string(value) +
                    " is outside [" + std::to_string(p->min) + ", " + std::to_string(p->max) + "]");
        }
        set_medium(vars_, m);
        for (const auto& p : def.parameters) {
            const auto it = values.find(p.name);
            vars_[p.name] = it != values.end() ? it->second : p.fallback;
        }
        vars_["r"] = 0.0;
        r_ = &vars_["r"];
        for (const auto& d : def.init) {
            const double v = vars_.evaluate(d.expression);
            vars_[d.name] = v;
        }
        vars_.define_all(rd_);
        rd_.SetExpr(def.rd.expression);
        if (!def.total_rd.expression.empty()) {
            total_ = vars_.evaluate(def.total_rd.expression);
        } else {
            // 2 pi int_0^inf R_d r dr = int 2 pi r^2 R_d d(ln r), r = l e^t, t in [-64, 48] about
            // the reduced mean free path l, in unit panels.
            const double l = 1 / m.sigma_t_reduced();
            std::vector<double> breaks;
            for (int t = -64; t <= 48; ++t) breaks.push_back(t);
            total_ = diffusion_detail::integrate(
                [&](double t) {
                    const double r = l * std::exp(t);
                    return 2 * kPi * r * r * eval_rd(r);
                },
                breaks, 1e-10);
        }
    }

    std::string name() const override { return def_.name; }
    double total_rd() const override { return total_; }
    bool includes_single_scattering() const override { return def_.single_scattering; }

  private:
    double eval_rd(double r) const override {
        // muparser's evaluation writes its own state: one evaluation at a time.
        std::lock_guard<std::mutex> lock(mutex_);
        *r_ = r;
        return rd_.Eval();
    }

    ExpressionProfileDef def_;
    mutable Variables vars_;
    double* r_ = nullptr;
    mutable mu::Parser rd_;
    mutable std::mutex mutex_;
    double total_ = 0;
};

}  // namespace

ExpressionProfileDef parse_expression_profile(const std::string& text, const std::string& path) {
    auto doc = ConfigDocument::parse_string(text, path);
    ConfigTable root = doc->root();
    ExpressionProfileDef def;
    def.path = path;
    def.name = std::filesystem::path(path).stem().string();
    Variables vars;  // what the expressions read so far, for the checks
    set_medium(vars, DiffusionMedium{1, 1, 0, 1.3});
    for (ConfigTable p : root.table_array("parameter")) {
        ExpressionProfileDef::Parameter q;
        q.name = p.string("name");
        if (!is_glsl_identifier(q.name)) p.fail("name", "'" + q.name + "' is not an identifier");
        if (reserved(q.name) || vars.has(q.name))
            p.fail("name", "'" + q.name +
                               "' is taken (r, pi, the medium's names and the other "
                               "parameters are)");
        q.min = p.number("min");
        q.max = p.number("max");
        if (!(q.min <= q.max)) p.fail("max", "max is below min");
        q.fallback = p.number("default", Range::closed(q.min, q.max));
        vars[q.name] = q.fallback;
        def.parameters.push_back(q);
    }
    ConfigTable prof = root.require_table("profile");
    def.single_scattering = prof.boolean("single_scattering", false);
    // Compiles `e` with the names known so far; a failure is located at the key (or item).
    auto check = [&](const std::string& e, const std::string& key, std::size_t item, bool with_r) {
        Variables seen = vars;
        if (with_r) seen["r"] = 1.0;
        try {
            (void)seen.evaluate(e);
        } catch (const mu::Parser::exception_type& x) {
            const std::string m = "expression '" + e + "': " + parser_message(x, seen);
            if (item == std::string::npos) prof.fail(key, m);
            prof.fail_item(key, item, m);
        }
    };
    const std::vector<std::string> init =
        prof.optional_string_list("init").value_or(std::vector<std::string>{});
    for (std::size_t i = 0; i < init.size(); ++i) {
        const auto eq = init[i].find('=');
        ExpressionProfileDef::Definition d;
        d.name = trim(init[i].substr(0, eq == std::string::npos ? 0 : eq));
        d.expression = eq == std::string::npos ? "" : trim(init[i].substr(eq + 1));
        if (eq == std::string::npos || !is_glsl_identifier(d.name))
            prof.fail_item("init", i, "expected 'name = expression', got '" + init[i] + "'");
        if (reserved(d.name) || vars.has(d.name))
            prof.fail_item("init", i, "'" + d.name + "' is already defined");
        check(d.expression, "init", i, false);
        vars[d.name] = 1.0;
        def.init.push_back(d);
    }
    def.rd = {"rd", prof.string("rd")};
    check(def.rd.expression, "rd", std::string::npos, true);
    if (auto t = prof.optional_string("total_rd")) {
        def.total_rd = {"total_rd", *t};
        check(*t, "total_rd", std::string::npos, false);
    }
    root.finish();
    def.text = text;
    return def;
}

ExpressionProfileDef read_expression_profile(const std::string& path) {
    return parse_expression_profile(read_input_file(path, "profile file"), path);
}

std::unique_ptr<DiffusionProfile> make_expression_profile(
    const ExpressionProfileDef& def, const DiffusionMedium& m,
    const std::map<std::string, double>& values) {
    return std::make_unique<ExpressionProfile>(def, m, values);
}

}  // namespace ssslab::approx
