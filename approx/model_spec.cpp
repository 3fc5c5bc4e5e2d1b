#include "approx/model_spec.h"

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <set>
#include <sstream>
#include <stdexcept>

namespace ssslab::approx {

namespace {

struct Known {
    const char* name;
    std::set<std::string> keys;
    const char* help;
};

const std::vector<Known>& known_models() {
    static const std::vector<Known> k = {
        {"svd", {"rank", "l1"}, "svd:rank=N[,l1] (Freude14 Eq. 5.5/5.12)"},
        {"preintegration", {}, "preintegration (Eq. 5.17)"},
        {"guided", {"k", "b"}, "guided:k=K[,b=B] (Eq. 5.19/5.20)"},
        {"manual",
         {"table_a1", "unit", "near", "far", "w", "fit"},
         "manual:table_a1,unit=mm|cm, manual:near=MM,far=MM,w=W or manual:fit=SIGNAL (Eq. "
         "5.21)"},
        {"deon", {"n"}, "deon:n=1..6 (d'Eon & Luebke 2007)"},
        {"ssss_skin", {}, "ssss_skin (Eq. 4.8, the separable-sss demo's kernel)"},
    };
    return k;
}

std::string list_models() {
    std::string s;
    for (const auto& m : known_models()) s += (s.empty() ? "" : "; ") + std::string(m.help);
    return s;
}

double parse_number(const std::string& spec, const std::string& key, const std::string& v) {
    char* end = nullptr;
    const double x = std::strtod(v.c_str(), &end);
    if (v.empty() || *end != '\0' || !std::isfinite(x))
        throw std::invalid_argument("model \"" + spec + "\": " + key + " must be a number, got \"" +
                                    v + "\"");
    return x;
}

}  // namespace

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
    return name == "svd" || name == "preintegration" || (name == "manual" && !flag("fit")) ||
           name == "ssss_skin";
}

ModelSpec parse_model(const std::string& text) {
    ModelSpec m;
    m.text = text;
    const size_t colon = text.find(':');
    m.name = text.substr(0, colon);
    const Known* known = nullptr;
    for (const auto& k : known_models())
        if (m.name == k.name) known = &k;
    if (!known)
        throw std::invalid_argument("unknown model \"" + m.name + "\"; models: " + list_models());
    if (colon != std::string::npos) {
        std::stringstream ss(text.substr(colon + 1));
        std::string item;
        while (std::getline(ss, item, ',')) {
            const size_t eq = item.find('=');
            const std::string key = item.substr(0, eq);
            const std::string value = eq == std::string::npos ? "" : item.substr(eq + 1);
            if (!known->keys.count(key)) {
                std::string keys;
                for (const auto& k : known->keys) keys += (keys.empty() ? "" : ", ") + k;
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
    if (m.name == "svd") {
        const double r = m.number("rank", 1);
        if (r < 1 || r > 64 || r != std::floor(r))
            throw std::invalid_argument("model \"" + text +
                                        "\": rank must be an integer in [1, 64]");
    } else if (m.name == "guided") {
        const double k = m.number("k", 1), b = m.number("b", 0);
        if (k < 0 || k > 4)
            throw std::invalid_argument("model \"" + text + "\": k must be in [0, 4]");
        if (b < 0) throw std::invalid_argument("model \"" + text + "\": b must be >= 0");
    } else if (m.name == "deon") {
        const double n = m.number("n", 1);
        if (n < 1 || n > 6 || n != std::floor(n))
            throw std::invalid_argument("model \"" + text + "\": n must be an integer in [1, 6]");
    } else if (m.name == "manual") {
        Signal sig;
        if (m.flag("fit") && (m.params.size() != 1 || !parse_signal(m.string("fit", ""), sig)))
            throw std::invalid_argument("model \"" + text +
                                        "\": fit takes a test signal (edge, circle_squares, dot, "
                                        "skin_shaded, skin_uniform) and no other parameter");
        if (m.flag("fit")) {
        } else if (m.flag("table_a1")) {
            const std::string u = m.string("unit", "");
            if (u != "mm" && u != "cm")
                throw std::invalid_argument("model \"" + text +
                                            "\": table_a1 needs unit=mm or unit=cm (the thesis "
                                            "does not state it)");
        } else {
            const double nr = m.number("near", -1), fr = m.number("far", -1), w = m.number("w", -1);
            if (!(nr > 0) || !(fr > 0) || !(w >= 0 && w <= 1))
                throw std::invalid_argument("model \"" + text +
                                            "\": give table_a1,unit=... or near=MM,far=MM,w=W with "
                                            "near, far > 0 and w in [0, 1]");
        }
    }
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
    ModelResult r;
    if (m.name == "svd") {
        r = svd_rank_n(k, static_cast<int>(m.number("rank", 1)), m.flag("l1"));
    } else if (m.name == "preintegration") {
        r = preintegration(k);
    } else if (m.name == "guided") {
        r = guided(k, {m.number("k", 1), m.number("b", 0)});
    } else if (m.name == "deon") {
        r = sum_of_gaussians(k, static_cast<int>(m.number("n", 1)));
    } else if (m.name == "manual") {
        double near, far, w;
        if (m.flag("fit")) {
            Signal sig;
            parse_signal(m.string("fit", ""), sig);
            if (!ctx.fit_images)
                throw std::invalid_argument("model \"" + m.text +
                                            "\" needs test-signal images (a kernel study)");
            const auto& [signal, exact] = ctx.fit_images(sig);
            r = fit_manual_two_gaussian(k, signal, exact, ctx.channel);
            r.kernel.model = m.label();
            return r;
        } else if (m.flag("table_a1")) {
            const auto& t = freude14_table_a1();
            const auto it = t.find(ctx.material);
            if (it == t.end())
                throw std::invalid_argument("model \"" + m.text +
                                            "\": Freude14 Table A.1 has no "
                                            "row for material \"" +
                                            ctx.material + "\"");
            const double unit = m.string("unit", "mm") == "cm" ? 10.0 : 1.0;
            near = it->second.sqrt_tau_near[ctx.channel] * unit;
            far = it->second.sqrt_tau_far[ctx.channel] * unit;
            w = it->second.w;
        } else {
            near = m.number("near", 0);
            far = m.number("far", 0);
            w = m.number("w", 0.5);
        }
        r = manual_two_gaussian(k, near, far, w);
        r.info["sqrt_tau_near_mm"] = near;
        r.info["sqrt_tau_far_mm"] = far;
        r.info["w"] = w;
    } else if (m.name == "ssss_skin") {
        r = ssss_skin_kernel(k, ctx.channel);
    } else {
        throw std::invalid_argument("unknown model \"" + m.name + "\"");
    }
    r.kernel.model = m.label();
    return r;
}

}  // namespace ssslab::approx
