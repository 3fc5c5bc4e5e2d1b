// What both passes of the GL lighting (realtime/gl/lighting_gl.h) share: the G-buffer's camera
// rays, the materials' boundaries, the lights seen directly. The C++ side prepends "#version";
// every function is the GLSL of the one named beside it in realtime/lighting.cpp or
// core/dielectric.h, in float. Positions are relative to the camera (u_* "_rel" uniforms are
// computed in double on the CPU), so that float keeps its precision in scenes far from the
// origin.

const float kPi = 3.14159265358979;
const float kInf = 1.0 / 0.0;

// The G-buffer (sample grid, rows of the frame upside down: GL's row 0 is the frame's last).
uniform sampler2D u_view_z;      // R32F view depth (+inf: nothing)
uniform isampler2D u_shape;      // R32I scene shape (-1: nothing)
uniform sampler2D u_ndc_x;       // W x 1: RasterCamera::SampleRays::ndc_x
uniform sampler2D u_ndc_y;       // H x 1: ndc_y, in the frame's row order
uniform vec3 u_forward, u_right, u_up;
uniform int u_height;            // sample rows

// Materials, one texel column each: row 0 (eta, alpha, c, kind: 0 diffuse, 1 medium), row 1
// (albedo / pi, slab entries).
uniform sampler2D u_mat;
// BoundaryTransmittance's GGX table per material (row m, u_cosines entries).
uniform sampler2D u_boundary;
uniform int u_cosines;

// Sphere lights (centre relative to the camera, radius, colour) and what a ray that meets no
// geometry sees: the environment's colour and the suns' discs.
const int kMaxSpheres = 16, kMaxSuns = 8;
uniform int u_spheres;
uniform vec4 u_sphere[kMaxSpheres];        // centre_rel, radius
uniform vec3 u_sphere_color[kMaxSpheres];
uniform int u_sphere_light[kMaxSpheres];   // index in Scene::lights
uniform vec3 u_environment;
uniform int u_suns;
uniform vec4 u_sun[kMaxSuns];              // direction, cos_max
uniform vec3 u_sun_radiance[kMaxSuns];     // colour / projected solid angle

ivec2 frame_sample(ivec2 gl_xy) { return ivec2(gl_xy.x, u_height - 1 - gl_xy.y); }

// RasterCamera::SampleRays::unnormalized of sample (sx, sy) of the frame.
vec3 unnormalized_ray(ivec2 s) {
    float nx = texelFetch(u_ndc_x, ivec2(s.x, 0), 0).r;
    float ny = texelFetch(u_ndc_y, ivec2(s.y, 0), 0).r;
    return u_forward + u_right * nx + u_up * ny;
}

// core/dielectric.h fresnel_dielectric
float fresnel_dielectric(float cos_i, float eta) {
    cos_i = min(cos_i, 1.0);
    float sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if (sin2_t >= 1.0) return 1.0;
    float cos_t = sqrt(1.0 - sin2_t);
    if (eta == 1.0) return 0.0;
    float rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    float rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    return 0.5 * (rs * rs + rp * rp);
}

vec4 material_row0(int m) { return texelFetch(u_mat, ivec2(m, 0), 0); }
vec4 material_row1(int m) { return texelFetch(u_mat, ivec2(m, 1), 0); }

// BoundaryTransmittance::operator() of material m (row 0: eta, alpha).
float boundary_T(int m, float mu) {
    if (!(mu > 0.0)) return 0.0;
    mu = min(mu, 1.0);
    vec4 b = material_row0(m);
    if (b.y == 0.0) return 1.0 - fresnel_dielectric(mu, b.x);
    float x = mu * float(u_cosines - 1);
    int k = min(int(x), u_cosines - 2);
    float t = x - float(k);
    float t0 = texelFetch(u_boundary, ivec2(k, m), 0).r;
    float t1 = texelFetch(u_boundary, ivec2(k + 1, m), 0).r;
    return t0 + t * (t1 - t0);
}

// core/vec3.h ray_sphere_hit (d a unit vector)
float ray_sphere_hit(vec3 o, vec3 d, vec3 c, float r) {
    vec3 oc = o - c;
    float b = dot(oc, d), cc = dot(oc, oc) - r * r;
    float disc = b * b - cc;
    if (disc < 0.0) return kInf;
    float s = sqrt(disc);
    if (-b - s > 0.0) return -b - s;
    if (-b + s > 0.0) return -b + s;
    return kInf;
}

// lighting.cpp nearest_sphere: the nearest sphere light along from + t d; -1 if none.
int nearest_sphere(vec3 from, vec3 d, out float tl) {
    int hit = -1;
    tl = kInf;
    for (int k = 0; k < u_spheres; ++k) {
        float t = ray_sphere_hit(from, d, u_sphere[k].xyz, u_sphere[k].w);
        if (t < tl) {
            tl = t;
            hit = k;
        }
    }
    return hit;
}

// lighting.cpp sky
vec3 sky(vec3 d) {
    vec3 L = u_environment;
    for (int k = 0; k < u_suns; ++k)
        if (dot(d, u_sun[k].xyz) >= u_sun[k].w) L += u_sun_radiance[k];
    return L;
}
