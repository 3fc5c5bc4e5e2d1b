#include "approx/bssrdf_file.h"

#include "core/atomic_file.h"
#include "core/error.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <sstream>

namespace ssslab::approx {

namespace {

std::vector<std::string> words(const std::string& line) {
    std::istringstream in(line);
    std::vector<std::string> w;
    for (std::string s; in >> s;) w.push_back(s);
    return w;
}

bool blank(const std::string& line) {
    return std::all_of(line.begin(), line.end(), [](unsigned char c) { return std::isspace(c); });
}

class Parser {
  public:
    Parser(const std::string& text, const std::string& path) : path_(path) {
        std::istringstream in(text);
        for (std::string l; std::getline(in, l);) {
            if (!l.empty() && l.back() == '\r') l.pop_back();
            lines_.push_back(l);
        }
        file_.path = path;
    }

    BssrdfFile parse() {
        size_t i = 0;
        while (i < lines_.size() && blank(lines_[i])) ++i;
        if (i == lines_.size()) fail(1, "", "empty file: expected the attribute line");
        attributes(i);
        ++i;
        for (; i < lines_.size(); ++i) {
            const std::vector<std::string> w = words(lines_[i]);
            if (w.empty()) continue;
            if (w[0] == "::begin") {
                i = section(i, w);
                continue;
            }
            if (w[0] == "::end")
                fail(line(i), w.size() > 1 ? w[1] : "", "'::end' without a '::begin'");
            fail(line(i), "",
                 "text outside a section (expected '::begin NAME'; sections hold everything "
                 "after the attribute line)");
        }
        if (!file_.shader)
            fail(0, "shader",
                 "no 'shader' section: the file must define vec3 Bssrdf(vec3 Xi, vec3 Wi, "
                 "vec3 Xo, vec3 Wo)");
        return std::move(file_);
    }

  private:
    static int line(size_t i) { return static_cast<int>(i) + 1; }

    [[noreturn]] void fail(int at, const std::string& key, const std::string& message) const {
        const std::string text =
            at > 0 && static_cast<size_t>(at) <= lines_.size() ? lines_[at - 1] : "";
        throw InputError({path_, at, 0}, key, message, text);
    }

    // [Bitterli13 §A.2, "Attributes"]: analytic (mandatory), radial, no_wi, no_wo.
    void attributes(size_t i) {
        bool analytic = false;
        for (const std::string& a : words(lines_[i])) {
            if (a == "analytic")
                analytic = true;
            else if (a == "radial")
                file_.radial = true;
            else if (a == "no_wi")
                file_.no_wi = true;
            else if (a == "no_wo")
                file_.no_wo = true;
            else if (a.rfind("::", 0) == 0)
                fail(line(i), "",
                     "the first line must list the attributes (analytic, radial, no_wi, no_wo)");
            else
                fail(line(i), a,
                     "unknown attribute '" + a + "' (known: analytic, radial, no_wi, no_wo)");
        }
        if (!analytic)
            fail(line(i), "analytic", "the attribute 'analytic' is mandatory [Bitterli13 §A.2]");
    }

    // A section from its `::begin` line `b`; returns the index of its `::end` line.
    size_t section(size_t b, const std::vector<std::string>& w) {
        if (w.size() != 2 || !is_glsl_identifier(w[1]))
            fail(line(b), "", "'::begin' takes one section name, e.g. '::begin shader'");
        const std::string name = w[1];
        size_t e = b + 1;
        for (; e < lines_.size(); ++e) {
            const std::vector<std::string> v = words(lines_[e]);
            if (v.empty()) continue;
            if (v[0] == "::begin")
                fail(line(e), name,
                     "'::begin' inside section '" + name + "' (opened on line " +
                         std::to_string(line(b)) + "): close it with '::end " + name + "' first");
            if (v[0] == "::end") {
                if (v.size() != 2 || v[1] != name)
                    fail(line(e), name,
                         "'" + lines_[e] + "' closes section '" + name + "' (opened on line " +
                             std::to_string(line(b)) + "): expected '::end " + name + "'");
                break;
            }
        }
        if (e == lines_.size())
            fail(line(b), name, "section '" + name + "' has no '::end " + name + "'");
        BssrdfSection s;
        s.name = name;
        s.first_line = line(b + 1);
        for (size_t k = b + 1; k < e; ++k) s.code += lines_[k] + "\n";
        if (name == "parameters") {
            once(!seen_parameters_, b, name);
            seen_parameters_ = true;
            for (size_t k = b + 1; k < e; ++k) parameter(k);
        } else if (name == "initializer") {
            once(!file_.initializer, b, name);
            file_.initializer = std::move(s);
        } else if (name == "diffuseReflectance") {
            once(!file_.diffuse_reflectance, b, name);
            file_.diffuse_reflectance = std::move(s);
        } else if (name == "shader") {
            once(!file_.shader, b, name);
            file_.shader = std::move(s);
        } else {
            file_.ignored_sections.push_back(name);  // "it is ignored" [Bitterli13 §A.2]
        }
        return e;
    }

    void once(bool first, size_t b, const std::string& name) const {
        if (!first) fail(line(b), name, "section '" + name + "' is given twice");
    }

    double number(size_t k, const std::string& key, const std::string& s) const {
        errno = 0;
        char* end = nullptr;
        const double v = std::strtod(s.c_str(), &end);
        if (s.empty() || *end != '\0' || errno == ERANGE || !std::isfinite(v))
            fail(line(k), key, "'" + s + "' is not a finite number");
        return v;
    }

    // [Bitterli13 §A.2, "Parameters Section"].
    void parameter(size_t k) {
        const std::vector<std::string> w = words(lines_[k]);
        if (w.empty()) return;
        BssrdfParameter p;
        p.line = line(k);
        const std::string& type = w[0];
        const std::string key = w.size() > 1 ? w[1] : type;
        size_t values = 0;
        if (type == "float") {
            p.type = BssrdfParameter::Type::kFloat;
            values = 3;
        } else if (type == "bool") {
            p.type = BssrdfParameter::Type::kBool;
            values = 1;
        } else if (type == "color") {
            p.type = BssrdfParameter::Type::kColor;
            values = 3;
        } else {
            fail(line(k), type,
                 "unknown parameter type '" + type +
                     "' (expected 'float NAME MIN MAX DEFAULT', 'bool NAME DEFAULT' or "
                     "'color NAME R G B')");
        }
        static const char* const forms[] = {"float NAME MIN MAX DEFAULT", "bool NAME DEFAULT",
                                            "color NAME R G B"};
        if (w.size() != 2 + values)
            fail(line(k), key,
                 "a " + type + " parameter is declared as '" + forms[static_cast<int>(p.type)] +
                     "'");
        p.name = w[1];
        if (!is_glsl_identifier(p.name))
            fail(line(k), p.name, "'" + p.name + "' is not a GLSL identifier");
        const auto& reserved = bssrdf_reserved_names();
        if (std::find(reserved.begin(), reserved.end(), p.name) != reserved.end())
            fail(line(k), p.name,
                 "'" + p.name +
                     "' is defined by the application (the medium's "
                     "SigmaA, SigmaS, G, IOR and PI)");
        if (file_.find_parameter(p.name))
            fail(line(k), p.name, "parameter '" + p.name + "' is declared twice");
        if (p.type == BssrdfParameter::Type::kBool) {
            const std::string& v = w[2];
            if (v == "true" || v == "1")
                p.fallback[0] = 1;
            else if (v == "false" || v == "0")
                p.fallback[0] = 0;
            else
                fail(line(k), p.name, "a bool's default is true, false, 1 or 0, not '" + v + "'");
        } else if (p.type == BssrdfParameter::Type::kFloat) {
            p.min = number(k, p.name, w[2]);
            p.max = number(k, p.name, w[3]);
            p.fallback[0] = number(k, p.name, w[4]);
            if (!(p.min <= p.max))
                fail(line(k), p.name, "the minimum " + w[2] + " exceeds the maximum " + w[3]);
            if (p.fallback[0] < p.min || p.fallback[0] > p.max)
                fail(line(k), p.name,
                     "the default " + w[4] + " is outside [" + w[2] + ", " + w[3] + "]");
        } else {
            for (int c = 0; c < 3; ++c) p.fallback[c] = number(k, p.name, w[2 + c]);
        }
        file_.parameters.push_back(std::move(p));
    }

    std::string path_;
    std::vector<std::string> lines_;
    BssrdfFile file_;
    bool seen_parameters_ = false;
};

}  // namespace

bool is_glsl_identifier(const std::string& s) {
    if (s.empty() || !(std::isalpha(static_cast<unsigned char>(s[0])) || s[0] == '_')) return false;
    return std::all_of(s.begin(), s.end(),
                       [](unsigned char c) { return std::isalnum(c) || c == '_'; });
}

const BssrdfParameter* BssrdfFile::find_parameter(const std::string& name) const {
    for (const auto& p : parameters)
        if (p.name == name) return &p;
    return nullptr;
}

const std::vector<std::string>& bssrdf_reserved_names() {
    static const std::vector<std::string> names = {"SigmaA", "SigmaS", "G", "IOR", "PI"};
    return names;
}

BssrdfFile parse_bssrdf(const std::string& text, const std::string& path) {
    BssrdfFile f = Parser(text, path).parse();
    f.text = text;
    return f;
}

void require_radial_profile(const BssrdfFile& f) {
    if (!f.radial || !f.no_wo)
        throw InputError({f.path, 1, 0}, "",
                         "a profile model needs the attributes 'radial' and 'no_wo' (R_d is the "
                         "exitance at a distance: a BSSRDF that depends on more than the distance "
                         "or on Wo is not a radial profile)");
}

BssrdfFile read_bssrdf(const std::string& path) {
    return parse_bssrdf(read_input_file(path, ".bssrdf file"), path);
}

}  // namespace ssslab::approx
