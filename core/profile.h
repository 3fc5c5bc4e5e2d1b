// A radially symmetric diffuse reflectance profile R_d(r) per RGB channel, with the standard error
// of every bin: what the ground-truth engines produce and the kernel models consume
// (docs/architecture.md, "Data flow").
#pragma once

#include <array>
#include <string>
#include <vector>
#include "core/enum_names.h"

namespace ssslab {

enum class LengthUnit { kMm, kCm };
template <>
struct EnumNames<LengthUnit> {
    static constexpr std::array<std::pair<LengthUnit, std::string_view>, 2> table = {
        {{LengthUnit::kMm, "mm"}, {LengthUnit::kCm, "cm"}}};
};
const char* unit_name(LengthUnit u);  ///< "mm" or "cm"

struct RadialProfile {
    std::string name;
    double dr_cm = 0;  ///< bin width [cm]; bin i covers [i dr, (i+1) dr)
    int nr = 0;
    /// Mean reflectance over each annulus, R_d [1/cm^2] (weight per unit area per incident
    /// photon; MCML's Rd_r), and its standard error.
    std::array<std::vector<double>, 3> rd_per_cm2, se_per_cm2;
    /// Total diffuse reflectance (including beyond the grid) and its standard error [-].
    std::array<double, 3> rd_total{}, rd_total_se{};
    /// Part of the total diffuse reflectance that left beyond r = nr dr (not in any bin) [-].
    std::array<double, 3> beyond{}, beyond_se{};
    /// Specular reflectance at entry [-] (R_d carries the factor 1 - Rsp, as in MCML).
    std::array<double, 3> rsp{};

    /// CSV with a header row; lengths and R_d in the given unit (mm: R_d per mm^2).
    std::string to_csv(LengthUnit unit) const;
};

/// Parse a CSV written by to_csv() (either unit). Throws InputError.
RadialProfile read_profile_csv(const std::string& path);

}  // namespace ssslab
