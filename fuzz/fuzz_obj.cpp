// Wavefront OBJ meshes (core/mesh.h: tinyobjloader and ssslab's checks of what it returns). The
// loader reads files, so each input goes through a file of its own in /dev/shm (or /tmp).
#include "core/mesh.h"
#include "fuzz/fuzz_target.h"

#include <cstdio>
#include <filesystem>
#include <string>

#include <unistd.h>

namespace {

std::string scratch_path() {
    const char* dir = std::filesystem::is_directory("/dev/shm") ? "/dev/shm" : "/tmp";
    return std::string(dir) + "/ssslab-fuzz-" + std::to_string(::getpid()) + ".obj";
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    static const std::string path = scratch_path();
    if (std::FILE* f = std::fopen(path.c_str(), "wb")) {
        if (size) std::fwrite(data, 1, size, f);
        std::fclose(f);
    } else {
        return 0;
    }
    const int r = ssslab::fuzz::accept_or_refuse([&] { ssslab::load_obj(path); });
    std::remove(path.c_str());
    return r;
}
