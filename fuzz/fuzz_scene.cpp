// Scene files (core/scene.h): camera, lights, shapes, media, materials. Mesh files resolve
// against fuzz/corpus/meshes, which holds the meshes the seed scenes name.
#include "core/scene.h"
#include "fuzz/fuzz_target.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    return ssslab::fuzz::accept_or_refuse([&] {
        ssslab::parse_scene(ssslab::fuzz::text(data, size), "fuzz.toml", SSSLAB_FUZZ_MESH_DIR);
    });
}
