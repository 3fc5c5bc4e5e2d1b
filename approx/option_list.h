// The variants of the image-space approximations as experiment configs name them:
// "key=value,key=value" (approx::parse_munoz "layers=8,t=0.001", approx::parse_jensen_buhler
// "density=4,threshold=0.05"). One reader for every such list: items in order, each key at most
// once, numbers that must be finite and whole numbers that must be whole; errors prefixed with
// the list's name, for the config reader to locate.
#pragma once

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace ssslab::approx {

class OptionList {
  public:
    /// Split `text`; throws std::invalid_argument for an item without '=' or a key given twice.
    OptionList(std::string what, const std::string& text) : what_(std::move(what)) {
        std::stringstream in(text);
        std::string item;
        while (std::getline(in, item, ',')) {
            const size_t eq = item.find('=');
            if (eq == std::string::npos) fail("\"" + item + "\" is not key=value");
            std::string key = item.substr(0, eq), v = item.substr(eq + 1);
            for (const auto& [k, x] : items_)
                if (k == key) fail("\"" + key + "\" is given twice");
            items_.emplace_back(std::move(key), std::move(v));
        }
    }
    const std::vector<std::pair<std::string, std::string>>& items() const { return items_; }

    /// A finite number.
    double number(const std::string& key, const std::string& v) const {
        size_t used = 0;
        double x = 0;
        try {
            x = std::stod(v, &used);
        } catch (const std::exception&) {
            used = 0;
        }
        if (used != v.size() || v.empty() || !std::isfinite(x))
            throw std::invalid_argument(what_ + " \"" + key + "\": \"" + v + "\" is not a number");
        return x;
    }
    /// A whole number (clamped to +-1e9 for the caller's range check).
    int whole(const std::string& key, const std::string& v) const {
        const double x = number(key, v);
        if (x != std::floor(x))
            throw std::invalid_argument(what_ + " \"" + key + "\": " + v +
                                        " is not a whole number");
        return static_cast<int>(std::clamp(x, -1e9, 1e9));
    }
    [[noreturn]] void fail(const std::string& what) const {
        throw std::invalid_argument(what_ + ": " + what);
    }

  private:
    std::string what_;
    std::vector<std::pair<std::string, std::string>> items_;
};

}  // namespace ssslab::approx
