// Content hashes: the key of every cached artifact is a hash of everything that determines it
// (docs/architecture.md, "Data flow"). The hashed text is canonical: fields are named, numbers are
// written with every significant digit, so a value read as 1e6 or 1000000 hashes alike and a change
// in the 17th digit does not go unnoticed. XXH3-128 (libxxhash) is the hash.
#pragma once

#include "core/vec3.h"

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace ssslab {

/// A 32-bit integer hash (lowbias32, C. Wellons): well mixed, cheap, the same everywhere. Seeds of
/// procedural noise, jitter and scrambles; not a content hash (ContentKey below is).
inline std::uint32_t hash32(std::uint32_t x) {
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

/// Builds the canonical description of an artifact and hashes it.
class ContentKey {
  public:
    explicit ContentKey(std::string_view kind) { text_ = std::string(kind) + "\n"; }

    ContentKey& add(std::string_view name, std::string_view value);
    ContentKey& add(std::string_view name, const char* value) {
        return add(name, std::string_view(value));
    }
    ContentKey& add(std::string_view name, double value);
    ContentKey& add(std::string_view name, std::int64_t value);
    ContentKey& add(std::string_view name, std::uint64_t value);
    ContentKey& add(std::string_view name, int value) {
        return add(name, static_cast<std::int64_t>(value));
    }
    ContentKey& add(std::string_view name, bool value) {
        return add(name, value ? "true" : "false");
    }
    ContentKey& add(std::string_view name, const std::array<double, 3>& value);
    ContentKey& add(std::string_view name, const Vec3& value) {
        return add(name, std::array<double, 3>{value.x, value.y, value.z});
    }
    ContentKey& add(std::string_view name, const std::vector<double>& value);

    /// The canonical text (for --dry-run --verbose and for debugging a key).
    const std::string& text() const { return text_; }
    /// 32 hex digits of XXH3-128 of the canonical text.
    std::string hex() const;

  private:
    std::string text_;
};

/// XXH3-128 of arbitrary bytes as 32 hex digits.
std::string hash_hex(std::string_view bytes);

/// XXH3-128 of a file's content (IoError naming the file if it cannot be read).
std::string file_hash_hex(const std::string& path);

/// What differs between two canonical key texts (ContentKey::text(); other line-oriented
/// fingerprints work too): up to `max_items` items such as `materials[0].sigma_a_per_cm: was
/// 1, 2, 3, now 1, 2, 4`, `shapes[1].mesh: content changed` (a 32-digit hash),
/// `x = 3: only in the earlier input`, `y = 1: new`, joined by "; ", then "and N more". Empty
/// when the texts are equal.
std::string key_difference(std::string_view before, std::string_view now, int max_items = 4);

}  // namespace ssslab
