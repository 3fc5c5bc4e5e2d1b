// ssslab's commands with one more kernel model: the model registers itself in the same table the
// built-in models are entries of, then `custom_model run three_gaussian.toml` scores it beside
// them with the kernel-study code, against MCML ground truth.
#include "experiments/cli/commands.h"
#include "three_gaussian.h"

int main(int argc, char** argv) {
    custom::register_three_gaussian();
    return ssslab::cli::main_distributed(argc, argv);
}
