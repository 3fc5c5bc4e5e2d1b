#include "volpath/embree_scene.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace ssslab::volpath {

struct EmbreeScene::Impl {
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
    std::vector<std::vector<Vec3>> normals;  // per shape, per triangle (double precision)
};

namespace {

std::string device_error(RTCDevice d) {
    switch (rtcGetDeviceError(d)) {
        case RTC_ERROR_NONE:
            return "no error";
        case RTC_ERROR_INVALID_ARGUMENT:
            return "invalid argument";
        case RTC_ERROR_INVALID_OPERATION:
            return "invalid operation";
        case RTC_ERROR_OUT_OF_MEMORY:
            return "out of memory";
        case RTC_ERROR_UNSUPPORTED_CPU:
            return "unsupported CPU";
        case RTC_ERROR_CANCELLED:
            return "cancelled";
        default:
            return "unknown error";
    }
}

}  // namespace

EmbreeScene::EmbreeScene(const std::vector<const TriangleMesh*>& meshes) : impl_(new Impl) {
    impl_->device = rtcNewDevice(nullptr);  // builds use all threads; queries the caller's
    if (!impl_->device) throw std::runtime_error("Embree: cannot create a device");
    impl_->scene = rtcNewScene(impl_->device);
    rtcSetSceneBuildQuality(impl_->scene, RTC_BUILD_QUALITY_HIGH);
    rtcSetSceneFlags(impl_->scene, RTC_SCENE_FLAG_ROBUST);
    double extent = 0;
    for (std::size_t k = 0; k < meshes.size(); ++k) {
        const TriangleMesh& m = *meshes[k];
        RTCGeometry g = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
        auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0,
                                                              RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                              m.positions.size()));
        auto* ix = static_cast<unsigned*>(
            rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                    3 * sizeof(unsigned), m.triangles.size()));
        if (!v || !ix) throw std::runtime_error("Embree: " + device_error(impl_->device));
        for (std::size_t i = 0; i < m.positions.size(); ++i) {
            v[3 * i] = static_cast<float>(m.positions[i].x);
            v[3 * i + 1] = static_cast<float>(m.positions[i].y);
            v[3 * i + 2] = static_cast<float>(m.positions[i].z);
            extent = std::max({extent, std::fabs(m.positions[i].x), std::fabs(m.positions[i].y),
                               std::fabs(m.positions[i].z)});
        }
        std::vector<Vec3> normals;
        normals.reserve(m.triangles.size());
        for (std::size_t i = 0; i < m.triangles.size(); ++i) {
            const auto& t = m.triangles[i];
            ix[3 * i] = t[0];
            ix[3 * i + 1] = t[1];
            ix[3 * i + 2] = t[2];
            normals.push_back(normalize(cross(m.positions[t[1]] - m.positions[t[0]],
                                              m.positions[t[2]] - m.positions[t[0]])));
        }
        impl_->normals.push_back(std::move(normals));
        rtcCommitGeometry(g);
        const unsigned id = rtcAttachGeometry(impl_->scene, g);
        rtcReleaseGeometry(g);
        if (id != k) throw std::runtime_error("Embree: unexpected geometry id");
        triangles_ += m.triangles.size();
    }
    rtcCommitScene(impl_->scene);
    if (rtcGetDeviceError(impl_->device) != RTC_ERROR_NONE)
        throw std::runtime_error("Embree: " + device_error(impl_->device));
    // Single precision: positions carry a relative error of 2^-24; leave a few hundred ulps.
    epsilon_ = std::max(1e-9, 4e-5 * extent);
}

EmbreeScene::~EmbreeScene() {
    if (impl_->scene) rtcReleaseScene(impl_->scene);
    if (impl_->device) rtcReleaseDevice(impl_->device);
}

RayHit EmbreeScene::intersect(const Vec3& o, const Vec3& d, double t_min, double t_max) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRayHit rh{};
    rh.ray.org_x = static_cast<float>(o.x);
    rh.ray.org_y = static_cast<float>(o.y);
    rh.ray.org_z = static_cast<float>(o.z);
    rh.ray.dir_x = static_cast<float>(d.x);
    rh.ray.dir_y = static_cast<float>(d.y);
    rh.ray.dir_z = static_cast<float>(d.z);
    rh.ray.tnear = static_cast<float>(t_min);
    rh.ray.tfar =
        std::isfinite(t_max) ? static_cast<float>(t_max) : std::numeric_limits<float>::infinity();
    rh.ray.mask = 0xffffffffu;
    rh.ray.flags = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(impl_->scene, &ctx, &rh);
    RayHit out;
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return out;
    out.t = rh.ray.tfar;
    out.shape = rh.hit.geomID;
    out.triangle = rh.hit.primID;
    out.normal = impl_->normals[out.shape][out.triangle];
    return out;
}

bool EmbreeScene::occluded(const Vec3& o, const Vec3& d, double t_min, double t_max) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRay r{};
    r.org_x = static_cast<float>(o.x);
    r.org_y = static_cast<float>(o.y);
    r.org_z = static_cast<float>(o.z);
    r.dir_x = static_cast<float>(d.x);
    r.dir_y = static_cast<float>(d.y);
    r.dir_z = static_cast<float>(d.z);
    r.tnear = static_cast<float>(t_min);
    r.tfar =
        std::isfinite(t_max) ? static_cast<float>(t_max) : std::numeric_limits<float>::infinity();
    r.mask = 0xffffffffu;
    r.flags = 0;
    rtcOccluded1(impl_->scene, &ctx, &r);
    return r.tfar < 0;  // Embree sets tfar to -inf on a hit
}

}  // namespace ssslab::volpath
