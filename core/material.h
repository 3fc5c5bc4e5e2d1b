// Homogeneous scattering media per RGB channel, and the measured materials of the papers.
//
// Units: coefficients are stored per centimetre (MCML's unit) and the unit is in every field
// name. Configs state their unit in the key (sigma_a_per_mm or sigma_a_per_cm); conversion
// happens only in medium_from_config().
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

namespace ssslab {

class ConfigTable;
class ContentKey;
struct Range;

/// One RGB channel index: 0 = R, 1 = G, 2 = B.
inline constexpr const char* kChannelNames[3] = {"R", "G", "B"};

/// One layer of a layered slab below the first (see Medium::lower_layers). Units as in Medium.
/// A layer with sigma_a = sigma_s = 0 in every channel is clear (glass): light crosses it in a
/// straight line, as in MCML.
struct MediumLayer {
    std::array<double, 3> sigma_a_per_cm{};  ///< absorption coefficient [1/cm]
    std::array<double, 3> sigma_s_per_cm{};  ///< scattering coefficient [1/cm]
    std::array<double, 3> g{};               ///< Henyey-Greenstein anisotropy [-]
    double eta = 1.0;                        ///< index of refraction [-]
    double thickness_cm = 1e8;               ///< [cm]; 1e8 (last layer only) is "quasi-infinite"

    double sigma_t(int c) const { return sigma_a_per_cm[c] + sigma_s_per_cm[c]; }
    /// Reduced mean free path 1 / (sigma_a + sigma_s (1 - g)) [cm] (infinite for glass).
    double mfp_cm(int c) const {
        return 1.0 / (sigma_a_per_cm[c] + sigma_s_per_cm[c] * (1.0 - g[c]));
    }
    bool clear() const {
        for (int c = 0; c < 3; ++c)
            if (sigma_t(c) != 0.0) return false;
        return true;
    }
};

/// A slab of scattering medium, per RGB channel: homogeneous, or the top layer of a layered
/// stack (MCML's layered slabs [Wang95]) when `lower_layers` is not empty.
struct Medium {
    std::string name;
    std::array<double, 3> sigma_a_per_cm{};  ///< absorption coefficient [1/cm]
    std::array<double, 3> sigma_s_per_cm{};  ///< scattering coefficient [1/cm]
    std::array<double, 3> g{};               ///< Henyey-Greenstein anisotropy [-]
    double eta = 1.0;                        ///< index of refraction of the medium [-]
    double eta_above = 1.0;                  ///< ambient index above (light comes from here)
    double eta_below = 1.0;                  ///< ambient index below
    double thickness_cm = 1e8;               ///< slab thickness [cm]; 1e8 is "quasi-infinite"
    /// The layers below this one, top to bottom; empty for a homogeneous slab. The fields above
    /// describe the top layer (thickness_cm is then its thickness, and must be finite), eta_below
    /// is the ambient index under the last layer. Homogeneous-only models (diffusion profiles,
    /// the sphere) refuse layered media (require_homogeneous).
    std::vector<MediumLayer> lower_layers;

    bool layered() const { return !lower_layers.empty(); }
    /// All layers, top first (one for a homogeneous slab).
    std::vector<MediumLayer> layers() const;
    /// Sum of the layers' thicknesses [cm] (>= 1e8: quasi-infinite).
    double total_thickness_cm() const;

    /// Single-scattering albedo sigma_s / (sigma_a + sigma_s).
    double albedo(int c) const {
        return sigma_s_per_cm[c] / (sigma_a_per_cm[c] + sigma_s_per_cm[c]);
    }
    /// Mean free path 1 / (sigma_a + sigma_s') with sigma_s' = sigma_s (1 - g) [cm]
    /// (Freude14 §6.1 uses 1/sigma_t' with g = 0).
    double mfp_cm(int c) const {
        return 1.0 / (sigma_a_per_cm[c] + sigma_s_per_cm[c] * (1.0 - g[c]));
    }
};

/// Throws std::invalid_argument("<what> needs a homogeneous medium; <name> has N layers") for
/// a layered medium.
void require_homogeneous(const Medium& m, const std::string& what);

/// Every field of a medium that determines a result (coefficients of all channels and layers,
/// indices, thickness; not its name) as lines `<prefix>sigma_a_per_cm=...` of a content key:
/// the one description of a medium in fingerprints and cache keys.
void add_to_key(ContentKey& k, const std::string& prefix, const Medium& m);

/// A named measured material.
struct MaterialPreset {
    const char* name;
    Medium medium;
    const char* source;  ///< where the numbers come from
};

/// The eleven measured materials of [Freude14 Table 6.2] (Jensen et al. 2001 measurements,
/// converted to 1/cm; g = 0 so sigma_s is the reduced scattering coefficient; thickness 1e8 cm,
/// quasi-infinite). Marble has eta = 1.5, all others 1.3. JimenezSupp §G lists the same numbers in
/// 1/mm.
const std::vector<MaterialPreset>& freude14_materials();

/// The five main materials of Freude14 ch. 6 (Apple, Marble, Ketchup, Skin1, Wholemilk).
const std::vector<std::string>& freude14_main_materials();

/// Look up a preset by name (case-insensitive). nullopt if unknown.
std::optional<Medium> find_material(const std::string& name);
/// The preset names, comma-separated, for error messages.
std::string material_names();
/// The message for a preset name that does not exist: `unknown material "name" (did you mean
/// "Skin1"?); known materials: Apple, ...` (the suggestion only when one is near).
std::string unknown_material_message(const std::string& name);

/// A length given as <base>_mm or <base>_cm (not both), in cm; nullopt if neither is given.
std::optional<double> optional_length_cm(ConfigTable& t, const std::string& base, const Range& r);

/// Read a medium from a config table: either `preset = "Skin1"` (optionally with `thickness_cm`
/// or `thickness_mm`, `eta_above`, `eta_below`), or explicit coefficients with their unit in the
/// key: sigma_a_per_mm / sigma_a_per_cm, sigma_s_per_mm / sigma_s_per_cm, g (in [-1, 1]; the
/// original MCML rejects g < 0, ssslab's engines do not), eta; or a layered slab: `eta_above`,
/// `eta_below` and an array of tables `[[...layers]]`, top first, each a preset or explicit
/// coefficients with its thickness (required for all but the last layer, whose default is
/// quasi-infinite).
Medium medium_from_config(ConfigTable& t);

/// Records into `t` the medium as simulated, whatever it was read from (a preset by name, explicit
/// coefficients, layers): per layer, top first, sigma_a_per_cm, sigma_s_per_cm, g (RGB), eta and
/// thickness_cm, and the ambient indices eta_above and eta_below (the boundary both engines
/// simulate: smooth Fresnel interfaces between them and the layers).
void record_simulated(ConfigTable& t, const Medium& m);

/// Only the coefficients and index of a medium from a config table (a preset or explicit
/// coefficients as above, no thickness or ambient indices): for media bound to scene shapes.
Medium medium_coefficients_from_config(ConfigTable& t);

}  // namespace ssslab
