// Experiment configs (experiments/runner/experiment.h): the TOML of `ssslab run` and `check`,
// every section and the variant strings inside them.
#include "experiments/runner/experiment.h"
#include "fuzz/fuzz_target.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    return ssslab::fuzz::accept_or_refuse(
        [&] { ssslab::runner::parse_experiment(ssslab::fuzz::text(data, size), "fuzz.toml"); });
}
