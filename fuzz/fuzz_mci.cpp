// The .mci reader (mcml/mci.h): MCML's input files, original syntax and ssslab's extensions.
#include "fuzz/fuzz_target.h"
#include "mcml/mci.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    return ssslab::fuzz::accept_or_refuse(
        [&] { ssslab::mcml::parse_mci(ssslab::fuzz::text(data, size), "fuzz.mci"); });
}
