// Pass 1 of the GL lighting, first part (realtime/gl/lighting_gl.h): per sample what
// lighting.cpp's first loop writes: the facet normal and material, the kind of receiver, the
// exit weight, a smooth boundary's mirror reflection of the lights and sky, and what is seen
// directly (sphere lights, the environment and suns where nothing is). lighting_common.glsl is
// prepended.

uniform samplerBuffer u_facet;     // RGB32F facet normals (double on the CPU), all shapes
uniform isamplerBuffer u_shape_info;  // per shape: first facet, material
uniform sampler2D u_ray_t;         // R32F ray distance (0: nothing)
uniform isampler2D u_triangle;     // R32I triangle in its shape

layout(location = 0) out vec4 o_irradiance;    // 0
layout(location = 1) out vec4 o_specular;      // mirror reflection
layout(location = 2) out vec4 o_surface;       // what is seen directly
layout(location = 3) out vec4 o_translucency;  // 0 (a: thickness, 0)
layout(location = 4) out vec4 o_normal;        // facet normal, exit weight
layout(location = 5) out ivec2 o_kind;         // kind (0 none, 1 diffuse, 2 medium), material

void main() {
    ivec2 gxy = ivec2(gl_FragCoord.xy);
    ivec2 s = frame_sample(gxy);
    o_irradiance = vec4(0.0);
    o_specular = vec4(0.0);
    o_surface = vec4(0.0);
    o_translucency = vec4(0.0);
    o_normal = vec4(0.0);
    o_kind = ivec2(0, -1);
    int shape = texelFetch(u_shape, gxy, 0).r;
    vec3 du = unnormalized_ray(s);
    bool light_in_front = false;
    vec3 front_color = vec3(0.0);
    if (u_spheres > 0 || shape < 0) {
        vec3 d = normalize(du);
        float tl;
        int hit = nearest_sphere(vec3(0.0), d, tl);
        float ray_t = texelFetch(u_ray_t, gxy, 0).r;
        if (hit >= 0 && (shape < 0 || tl < ray_t)) {
            light_in_front = true;
            front_color = u_sphere_color[hit];
        }
        if (shape < 0) o_surface.rgb = hit >= 0 ? u_sphere_color[hit] : sky(d);
    }
    if (shape < 0) return;
    ivec2 info = texelFetch(u_shape_info, shape).rg;
    int mat = info.y;
    o_kind.y = mat;
    o_normal.xyz = texelFetch(u_facet, info.x + texelFetch(u_triangle, gxy, 0).r).rgb;
    if (light_in_front) {
        o_surface.rgb = front_color;
        return;
    }
    vec4 m0 = material_row0(mat);
    if (m0.w == 0.0) {
        o_kind.x = 1;
        return;
    }
    vec3 n = o_normal.xyz;
    vec3 wo = -normalize(du);
    float c = dot(n, wo);
    if (!(c > 0.0)) return;  // a medium seen from inside: not lit here
    o_kind.x = 2;
    o_normal.w = m0.z > 0.0 ? boundary_T(mat, c) / (kPi * m0.z) : 0.0;
    if (m0.y == 0.0) {
        // Mirror: F times what the reflected ray sees of the sphere lights, the environment
        // and the suns (unoccluded).
        vec3 rd = n * (2.0 * c) - wo;
        float F = fresnel_dielectric(c, m0.x);
        vec3 p = du * texelFetch(u_view_z, gxy, 0).r;
        float tb;
        int sl = nearest_sphere(p, rd, tb);
        o_specular.rgb = F * (sl >= 0 ? u_sphere_color[sl] : sky(rd));
    }
}
