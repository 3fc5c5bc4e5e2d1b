#include "approx/model_spec.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <mutex>
#include <sstream>
#include <stdexcept>

namespace ssslab::approx {

namespace {

double parse_number(const std::string& spec, const std::string& key, const std::string& v) {
    char* end = nullptr;
    const double x = std::strtod(v.c_str(), &end);
    if (v.empty() || *end != '\0' || !std::isfinite(x))
        throw std::invalid_argument("model \"" + spec + "\": " + key + " must be a number, got \"" +
                                    v + "\"");
    return x;
}

[[noreturn]] void bad(const ModelSpec& m, const std::string& what) {
    throw std::invalid_argument("model \"" + m.text + "\": " + what);
}

// ---- The built-in models: entries of the table like any registered from outside -------------

ModelFactory svd_factory() {
    ModelFactory f{"svd", {"rank", "l1"}, "svd:rank=N[,l1] (Freude14 Eq. 5.5/5.12)", "", {}, {},
                   {}};
    f.validate = [](const ModelSpec& m) {
        const double r = m.number("rank", 1);
        if (r < 1 || r > 64 || r != std::floor(r)) bad(m, "rank must be an integer in [1, 64]");
    };
    f.build = [](const ModelSpec& m, const Kernel2D& k, const ModelContext&) {
        return svd_rank_n(k, static_cast<int>(m.number("rank", 1)), m.flag("l1"));
    };
    return f;
}

ModelFactory preintegration_factory() {
    ModelFactory f{"preintegration", {}, "preintegration (Eq. 5.17)", "", {}, {}, {}};
    f.build = [](const ModelSpec&, const Kernel2D& k, const ModelContext&) {
        return preintegration(k);
    };
    return f;
}

ModelFactory guided_factory() {
    ModelFactory f{"guided", {"k", "b"}, "guided:k=K[,b=B] (Eq. 5.19/5.20)", "", {}, {}, {}};
    f.closed_form = [](const ModelSpec&) { return false; };
    f.validate = [](const ModelSpec& m) {
        const double k = m.number("k", 1), b = m.number("b", 0);
        if (k < 0 || k > 4) bad(m, "k must be in [0, 4]");
        if (b < 0) bad(m, "b must be >= 0");
    };
    f.build = [](const ModelSpec& m, const Kernel2D& k, const ModelContext&) {
        return guided(k, {m.number("k", 1), m.number("b", 0)});
    };
    return f;
}

ModelFactory deon_factory() {
    ModelFactory f{"deon", {"n"}, "deon:n=1..6 (d'Eon & Luebke 2007)", "", {}, {}, {}};
    f.closed_form = [](const ModelSpec&) { return false; };
    f.validate = [](const ModelSpec& m) {
        const double n = m.number("n", 1);
        if (n < 1 || n > 6 || n != std::floor(n)) bad(m, "n must be an integer in [1, 6]");
    };
    f.build = [](const ModelSpec& m, const Kernel2D& k, const ModelContext&) {
        return sum_of_gaussians(k, static_cast<int>(m.number("n", 1)));
    };
    return f;
}

ModelFactory manual_factory() {
    ModelFactory f{"manual",
                   {"table_a1", "unit", "near", "far", "w", "fit"},
                   "manual:table_a1,unit=mm|cm, manual:near=MM,far=MM,w=W or manual:fit=SIGNAL "
                   "(Eq. 5.21)",
                   "",
                   {},
                   {},
                   {}};
    f.closed_form = [](const ModelSpec& m) { return !m.flag("fit"); };
    f.validate = [](const ModelSpec& m) {
        Signal sig;
        if (m.flag("fit")) {
            if (m.params.size() != 1 || !parse_signal(m.string("fit", ""), sig))
                bad(m,
                    "fit takes a test signal (edge, circle_squares, dot, skin_shaded, "
                    "skin_uniform) and no other parameter");
        } else if (m.flag("table_a1")) {
            const std::string u = m.string("unit", "");
            if (u != "mm" && u != "cm")
                bad(m, "table_a1 needs unit=mm or unit=cm (the thesis does not state it)");
        } else {
            const double nr = m.number("near", -1), fr = m.number("far", -1), w = m.number("w", -1);
            if (!(nr > 0) || !(fr > 0) || !(w >= 0 && w <= 1))
                bad(m,
                    "give table_a1,unit=... or near=MM,far=MM,w=W with near, far > 0 and w in "
                    "[0, 1]");
        }
    };
    f.build = [](const ModelSpec& m, const Kernel2D& k, const ModelContext& ctx) {
        if (m.flag("fit")) {
            Signal sig;
            parse_signal(m.string("fit", ""), sig);
            if (!ctx.fit_images) bad(m, "needs test-signal images (a kernel study)");
            const auto& [signal, exact] = ctx.fit_images(sig);
            return fit_manual_two_gaussian(k, signal, exact, ctx.channel);
        }
        double near, far, w;
        if (m.flag("table_a1")) {
            const auto& t = freude14_table_a1();
            const auto it = t.find(ctx.material);
            if (it == t.end())
                bad(m, "Freude14 Table A.1 has no row for material \"" + ctx.material + "\"");
            const double unit = m.string("unit", "mm") == "cm" ? 10.0 : 1.0;
            near = it->second.sqrt_tau_near[ctx.channel] * unit;
            far = it->second.sqrt_tau_far[ctx.channel] * unit;
            w = it->second.w;
        } else {
            near = m.number("near", 0);
            far = m.number("far", 0);
            w = m.number("w", 0.5);
        }
        ModelResult r = manual_two_gaussian(k, near, far, w);
        r.info["sqrt_tau_near_mm"] = near;
        r.info["sqrt_tau_far_mm"] = far;
        r.info["w"] = w;
        return r;
    };
    return f;
}

ModelFactory ssss_skin_factory() {
    ModelFactory f{"ssss_skin", {}, "ssss_skin (Eq. 4.8, the separable-sss demo's kernel)", "", {},
                   {},          {}};
    f.build = [](const ModelSpec&, const Kernel2D& k, const ModelContext& ctx) {
        return ssss_skin_kernel(k, ctx.channel);
    };
    return f;
}

bool is_identifier(const std::string& s) {
    return !s.empty() &&
           s.find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789_") == std::string::npos;
}

// The table. std::map keeps references to its entries valid across insertions, so a factory
// found under the lock is used after it; entries are never removed.
struct Registry {
    std::mutex mutex;
    std::map<std::string, ModelFactory> factories;
    std::vector<std::string> order;  ///< built-ins first, then registration order (for help)

    Registry() {
        for (ModelFactory f : {svd_factory(), preintegration_factory(), guided_factory(),
                               manual_factory(), deon_factory(), ssss_skin_factory()}) {
            order.push_back(f.name);
            factories.emplace(f.name, std::move(f));
        }
    }
};

Registry& registry() {
    static Registry r;
    return r;
}

std::string list_models() {
    Registry& r = registry();
    std::lock_guard<std::mutex> lock(r.mutex);
    std::string s;
    for (const auto& name : r.order) s += (s.empty() ? "" : "; ") + r.factories.at(name).help;
    return s;
}

const ModelFactory* find_factory(const std::string& name) {
    Registry& r = registry();
    std::lock_guard<std::mutex> lock(r.mutex);
    const auto it = r.factories.find(name);
    return it == r.factories.end() ? nullptr : &it->second;
}

}  // namespace

void register_model(ModelFactory f) {
    if (!is_identifier(f.name))
        throw std::invalid_argument("register_model: the name \"" + f.name +
                                    "\" is not [a-z0-9_]+");
    if (!f.build) throw std::invalid_argument("register_model(\"" + f.name + "\"): no build");
    if (f.version.empty())
        throw std::invalid_argument("register_model(\"" + f.name +
                                    "\"): a version is required (it keys the studies' caches)");
    for (const auto& k : f.keys)
        if (!is_identifier(k))
            throw std::invalid_argument("register_model(\"" + f.name + "\"): the key \"" + k +
                                        "\" is not [a-z0-9_]+");
    if (f.help.empty()) f.help = f.name;
    Registry& r = registry();
    std::lock_guard<std::mutex> lock(r.mutex);
    if (r.factories.count(f.name))
        throw std::invalid_argument("register_model: a model named \"" + f.name +
                                    "\" exists already");
    r.order.push_back(f.name);
    r.factories.emplace(f.name, std::move(f));
}

std::vector<std::string> model_names() {
    Registry& r = registry();
    std::lock_guard<std::mutex> lock(r.mutex);
    std::vector<std::string> names;
    for (const auto& [name, f] : r.factories) names.push_back(name);  // sorted by the map
    return names;
}

double ModelSpec::number(const std::string& key, double fallback) const {
    const auto it = params.find(key);
    return it == params.end() ? fallback : parse_number(text, key, it->second);
}

std::string ModelSpec::string(const std::string& key, const std::string& fallback) const {
    const auto it = params.find(key);
    return it == params.end() ? fallback : it->second;
}

std::string ModelSpec::label() const {
    std::string s = name;
    for (const auto& [k, v] : params) {
        s += "_" + k;
        if (!v.empty()) s += v;
    }
    for (char& c : s)
        if (c == '.' || c == '=' || c == ',' || c == ':') c = c == '.' ? 'p' : '_';
    return s;
}

bool ModelSpec::closed_form() const {
    const ModelFactory* f = find_factory(name);
    return f && (!f->closed_form || f->closed_form(*this));
}

std::string ModelSpec::cache_text() const {
    const ModelFactory* f = find_factory(name);
    return f && !f->version.empty() ? text + "@" + f->version : text;
}

ModelSpec parse_model(const std::string& text) {
    ModelSpec m;
    m.text = text;
    const size_t colon = text.find(':');
    m.name = text.substr(0, colon);
    const ModelFactory* known = find_factory(m.name);
    if (!known)
        throw std::invalid_argument("unknown model \"" + m.name + "\"; models: " + list_models());
    if (colon != std::string::npos) {
        std::stringstream ss(text.substr(colon + 1));
        std::string item;
        while (std::getline(ss, item, ',')) {
            const size_t eq = item.find('=');
            const std::string key = item.substr(0, eq);
            const std::string value = eq == std::string::npos ? "" : item.substr(eq + 1);
            if (std::find(known->keys.begin(), known->keys.end(), key) == known->keys.end()) {
                std::vector<std::string> sorted(known->keys);
                std::sort(sorted.begin(), sorted.end());
                std::string keys;
                for (const auto& k : sorted) keys += (keys.empty() ? "" : ", ") + k;
                throw std::invalid_argument("model \"" + text + "\": unknown parameter \"" + key +
                                            "\" (" + m.name +
                                            " takes: " + (keys.empty() ? "nothing" : keys) + ")");
            }
            if (m.params.count(key))
                throw std::invalid_argument("model \"" + text + "\": \"" + key + "\" given twice");
            m.params[key] = value;
        }
    }
    // Validate values now, so that a bad config fails before any work.
    if (known->validate) known->validate(m);
    return m;
}

const std::map<std::string, TableA1Row>& freude14_table_a1() {
    // [Freude14 Table A.1]: sqrt(tau_n), sqrt(tau_f) per RGB channel and w.
    static const std::map<std::string, TableA1Row> t = {
        {"Apple", {{0.0495, 0.0455, 0.0372}, {1.1, 1.08, 0.926}, 0.368}},
        {"Ketchup", {{0.0907, 0.0331, 0.0331}, {1.5, 0.118, 0.0966}, 0.665}},
        {"Marble", {{0.0371, 0.0207, 0.015}, {0.663, 0.616, 0.558}, 0.234}},
        {"Skin1", {{0.429, 0.211, 0.03}, {1.15, 0.69, 0.471}, 0.533}},
        {"Wholemilk", {{0.0846, 0.0846, 0.0583}, {1.5, 1.39, 1.17}, 0.407}},
    };
    return t;
}

ModelResult build_model(const ModelSpec& m, const Kernel2D& k, const ModelContext& ctx) {
    const ModelFactory* f = find_factory(m.name);
    if (!f) throw std::invalid_argument("unknown model \"" + m.name + "\"");
    ModelResult r = f->build(m, k, ctx);
    if (r.kernel.n != k.n() || r.kernel.h_mm != k.h_mm())
        throw std::logic_error("model \"" + m.text + "\" built a kernel on another grid (n " +
                               std::to_string(r.kernel.n) + ", the kernel's " +
                               std::to_string(k.n()) + ")");
    r.kernel.model = m.label();
    return r;
}

}  // namespace ssslab::approx
