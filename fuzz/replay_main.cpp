// A main() for the fuzz targets without libFuzzer: runs the target once on each file named on
// the command line, or on each file in each folder named (the committed seeds and the inputs that
// once found a bug). The ordinary build compiles every target with it, so the tests replay the
// corpora with GCC and any sanitizer (tests/CMakeLists.txt, fuzz_replay_*).
#include "core/atomic_file.h"

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

int main(int argc, char** argv) {
    namespace fs = std::filesystem;
    std::vector<fs::path> files;
    for (int i = 1; i < argc; ++i) {
        const fs::path p = argv[i];
        if (fs::is_directory(p)) {
            for (const auto& e : fs::recursive_directory_iterator(p))
                if (e.is_regular_file()) files.push_back(e.path());
        } else if (fs::is_regular_file(p)) {
            files.push_back(p);
        } else {
            std::fprintf(stderr, "replay: no file or folder '%s'\n", argv[i]);
            return 2;
        }
    }
    for (const auto& f : files) {
        const std::string bytes = ssslab::read_file(f);
        LLVMFuzzerTestOneInput(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
    }
    std::printf("replay: %zu inputs, no failure\n", files.size());
    return files.empty() ? 1 : 0;
}
