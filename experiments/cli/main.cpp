// The `ssslab` command (experiments/cli/app.cpp).
#include "experiments/cli/commands.h"

int main(int argc, char** argv) {
    return ssslab::cli::main_distributed(argc, argv);
}
