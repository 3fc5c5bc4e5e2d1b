// What every fuzz target checks (fuzz/README.md): a reader given any bytes either accepts them or
// refuses them with the project's bad-input errors (InputError, InfeasibleError: a message naming
// the file, line and key, exit status 2 in the command line). Any other exception, a crash, a
// sanitizer report, a hang or a runaway allocation is a bug.
#pragma once

#include "core/error.h"

#include <cstddef>
#include <cstdint>
#include <string_view>

namespace ssslab::fuzz {

inline std::string_view text(const std::uint8_t* data, std::size_t size) {
    return {reinterpret_cast<const char*>(data), size};
}

template <class F>
int accept_or_refuse(F&& read) {
    try {
        read();
    } catch (const InputError&) {
    } catch (const InfeasibleError&) {
    }
    return 0;
}

}  // namespace ssslab::fuzz
