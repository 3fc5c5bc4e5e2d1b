// The .mco reader (mcml/mco.h): MCML's output files, read back by `ssslab compare` and the tests.
#include "fuzz/fuzz_target.h"
#include "mcml/mco.h"

#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    return ssslab::fuzz::accept_or_refuse(
        [&] { ssslab::mcml::parse_mco(std::string(ssslab::fuzz::text(data, size)), "fuzz.mco"); });
}
