#include "experiments/runner/check.h"

#include "core/config.h"
#include "core/error.h"
#include "core/format.h"
#include "core/provenance.h"
#include "core/stats.h"

#include <cmath>
#include <cstdio>
#include <iomanip>
#include <map>
#include <sstream>

namespace ssslab::runner {

namespace fs = std::filesystem;

fs::path baseline_path(const ExperimentRun& r, const CheckOptions& o) {
    return o.baselines / (r.exp.name + (r.quick ? ".quick" : "") + ".toml");
}

std::string baseline_toml(const ExperimentRun& r) {
    std::ostringstream os;
    os << "# Baseline of `ssslab check` for experiment " << r.exp.name
       << (r.quick ? " (--quick)" : "") << ".\n# Written by `ssslab check --update`; "
       << "committed on purpose.\n\n[baseline]\nexperiment = \"" << r.exp.name
       << "\"\nquick = " << (r.quick ? "true" : "false") << "\nrevision = \"" << git_revision()
       << "\"\ndate = \"" << utc_now() << "\"\n";
    for (const auto& m : r.metrics) {
        os << "\n[[metric]]\nname = \"" << m.name << "\"\nunit = \"" << m.unit
           << "\"\nvalue = " << format_g(m.value, 17);
        if (m.stochastic)
            os << "\nse = " << format_g(m.se, 17) << "\nkind = \"stochastic\"\n";
        else
            os << "\nkind = \"deterministic\"\ntolerance = " << format_g(m.tolerance, 17) << "\n";
    }
    return os.str();
}

CheckResult check_against_baseline(const ExperimentRun& r, const CheckOptions& o) {
    const fs::path path = baseline_path(r, o);
    std::error_code ec;
    if (!fs::exists(path, ec))
        throw InputError({path.string(), 0, 0}, "",
                         "no baseline for experiment " + r.exp.name +
                             (r.quick ? " (--quick)" : "") +
                             "; create it with `ssslab check --update` and commit it");
    auto doc = ConfigDocument::parse_file(path.string());
    ConfigTable root = doc->root();
    ConfigTable b = root.require_table("baseline");
    const std::string name = b.string("experiment");
    if (name != r.exp.name)
        b.fail("experiment", "baseline of \"" + name + "\", not \"" + r.exp.name + "\"");
    if (b.boolean("quick", false) != r.quick)
        b.fail("quick", r.quick ? "this baseline is of a full run, the check is --quick"
                                : "this baseline is of a --quick run, the check is full");
    (void)b.string("revision", "");
    (void)b.string("date", "");
    struct Base {
        double value, se, tolerance;
        bool stochastic;
    };
    std::map<std::string, Base> base;
    for (ConfigTable& m : root.table_array("metric")) {
        const std::string n = m.string("name");
        (void)m.string("unit", "");
        const double v = m.number("value");
        const std::string kind = m.choice("kind", "stochastic", {"stochastic", "deterministic"});
        Base x{v, 0, 0, kind == "stochastic"};
        if (x.stochastic)
            x.se = m.number("se", Range::nonnegative());
        else
            x.tolerance = m.number("tolerance", 0.0, Range::nonnegative());
        if (!base.emplace(n, x).second) m.fail("name", "metric \"" + n + "\" appears twice");
    }
    root.finish();

    CheckResult res;
    int stochastic = 0;
    for (const auto& m : r.metrics) stochastic += m.stochastic;
    const double alpha_each = sidak(o.alpha, stochastic);
    res.z_threshold = normal_quantile(1.0 - alpha_each / 2);
    std::map<std::string, bool> seen;
    for (const auto& m : r.metrics) {
        CheckRow row;
        row.name = m.name;
        row.current = m.value;
        row.current_se = m.se;
        row.stochastic = m.stochastic;
        seen[m.name] = true;
        const auto it = base.find(m.name);
        if (it == base.end()) {
            row.status = "new";
            res.rows.push_back(row);
            continue;
        }
        row.base = it->second.value;
        row.base_se = it->second.se;
        if (m.stochastic && it->second.stochastic) {
            const double s = std::sqrt(m.se * m.se + it->second.se * it->second.se);
            row.z =
                s > 0 ? (m.value - it->second.value) / s : (m.value == it->second.value ? 0 : 1e9);
            row.status = std::fabs(row.z) > res.z_threshold ? "REGRESSION"
                         : std::fabs(row.z) > 2.0           ? "moved"
                                                            : "ok";
        } else {
            const double tol = std::max(m.tolerance, it->second.tolerance) *
                               std::max(std::fabs(it->second.value), 1e-300);
            row.status = std::fabs(m.value - it->second.value) <= tol ? "ok" : "REGRESSION";
        }
        res.regressions += row.status == "REGRESSION";
        res.rows.push_back(row);
    }
    for (const auto& [n, x] : base) {
        if (seen.count(n)) continue;
        CheckRow row;
        row.name = n;
        row.base = x.value;
        row.base_se = x.se;
        row.stochastic = x.stochastic;
        row.status = "MISSING";
        ++res.regressions;
        res.rows.push_back(row);
    }
    return res;
}

void print_check(const CheckResult& c, const std::string& experiment, std::ostream& os,
                 bool verbose) {
    int shown = 0;
    for (const auto& r : c.rows) {
        if (!verbose && r.status == "ok") continue;
        if (shown++ == 0)
            os << "  " << std::left << std::setw(36) << "metric" << std::setw(28) << "baseline"
               << std::setw(28) << "current" << std::setw(9) << "z"
               << "status\n";
        char b[64], cur[64], z[32];
        std::snprintf(b, sizeof b, r.stochastic ? "%.6g +- %.2g" : "%.10g", r.base, r.base_se);
        std::snprintf(cur, sizeof cur, r.stochastic ? "%.6g +- %.2g" : "%.10g", r.current,
                      r.current_se);
        std::snprintf(z, sizeof z, r.stochastic ? "%+.2f" : "-", r.z);
        os << "  " << std::left << std::setw(36) << r.name << std::setw(28)
           << (r.status == "new" ? "-" : b) << std::setw(28) << (r.status == "MISSING" ? "-" : cur)
           << std::setw(9) << z << r.status << "\n";
    }
    os << experiment << ": " << c.rows.size() << " metrics, " << c.regressions << " regression"
       << (c.regressions == 1 ? "" : "s") << " (z threshold " << std::setprecision(3)
       << c.z_threshold << ")\n";
}

}  // namespace ssslab::runner
