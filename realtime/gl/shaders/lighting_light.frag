// Pass 1 of the GL lighting, second part (realtime/gl/lighting_gl.h): one light sample seen
// through one of its shadow views, added (blending GL_ONE, GL_ONE) to the layers the receiver
// pass started, light samples in scene order as lighting.cpp sums them. Per sample the body of
// lighting.cpp's light loop: the receiver, incident light, cube face, thickness from the map's
// first surface [Jimenez10], the normal-offset shadow test, sphere lights in the way, Lambert,
// the boundary's transmittance and GGX reflection, translucency through the slab table.
// lighting_common.glsl is prepended.

uniform sampler2D u_normal;  // receiver pass: facet normal, exit weight
uniform isampler2D u_kind;   // receiver pass: kind, material
uniform sampler2D u_slab;    // per material (row): thickness_mm, T rgb; u_mat row 1's w entries
uniform float u_unit_mm;

// The light sample (lighting.h LightSample), positions relative to the camera.
uniform bool u_directional, u_lobe, u_lobe_squared, u_thickness_view, u_lights;
uniform float u_lobe_scale, u_lobe_offset;  // the emitter's angular profile (core/light.h)
uniform vec3 u_w, u_pos_rel, u_lobe_n, u_value;
uniform int u_light;  // index in Scene::lights (sphere lights do not occlude themselves)

// Its views (ShadowView::Projection, origin relative to the camera), the one drawn u_view.
const int kMaxViews = 6;
uniform int u_views, u_view;
uniform vec3 u_origin_rel[kMaxViews], u_px[kMaxViews], u_py[kMaxViews], u_pw[kMaxViews];
uniform bool u_ortho;
uniform float u_near, u_texel;  // texel: 2 max(half_x, half_y) / size
uniform int u_size;
uniform bool u_need_map, u_shadows;
uniform float u_normal_offset, u_depth_bias;
uniform sampler2D u_map_depth;   // the view's map (GL rows: row 0 is the map's last)
uniform isampler2D u_map_shape;

layout(location = 0) out vec4 o_irradiance;
layout(location = 1) out vec4 o_specular;
layout(location = 2) out vec4 o_surface;
layout(location = 3) out vec4 o_translucency;  // a: thickness

// ShadowMap::texel_coords
bool texel_coords(vec3 c, out float fx, out float fy) {
    float u = c.x, w = c.y;
    fx = fy = 0.0;
    if (!u_ortho) {
        if (!(c.z > u_near)) return false;
        u /= c.z;
        w /= c.z;
    }
    fx = (u + 1.0) * 0.5 * float(u_size);
    fy = (1.0 - w) * 0.5 * float(u_size);
    return fx >= 0.0 && fy >= 0.0 && fx < float(u_size) && fy < float(u_size);
}
ivec2 map_texel(int x, int y) { return ivec2(x, u_size - 1 - y); }

// SlabTransmittance::at of material m (n entries)
vec3 slab_at(int m, int n, float d) {
    vec4 first = texelFetch(u_slab, ivec2(0, m), 0);
    if (!(d > first.x)) return first.yzw;
    vec4 last = texelFetch(u_slab, ivec2(n - 1, m), 0);
    if (d >= last.x) return last.yzw;
    int k = 1;
    while (k < n - 1 && texelFetch(u_slab, ivec2(k, m), 0).x <= d) ++k;
    vec4 a = texelFetch(u_slab, ivec2(k - 1, m), 0), b = texelFetch(u_slab, ivec2(k, m), 0);
    float t = (d - a.x) / (b.x - a.x);
    vec3 r;
    for (int c = 0; c < 3; ++c) {
        float ta = a[c + 1], tb = b[c + 1];
        r[c] = ta > 0.0 && tb > 0.0 ? exp(log(ta) + t * (log(tb) - log(ta))) : ta + t * (tb - ta);
    }
    return r;
}

// core/dielectric.h ggx::D, lambda and rough_dielectric_f for a reflection (both directions
// outside), cosines against the normal n.
float ggx_D(float cm, float alpha) {
    float c2 = cm * cm, t2 = max(0.0, 1.0 - c2) / c2;
    if (isinf(t2) || isnan(t2)) return 0.0;
    float e = 1.0 + t2 / (alpha * alpha);
    return 1.0 / (kPi * alpha * alpha * c2 * c2 * e * e);
}
float ggx_lambda(float c, float alpha) {
    float c2 = c * c, t2 = max(0.0, 1.0 - c2) / c2;
    if (isinf(t2) || isnan(t2)) return 0.0;
    return 0.5 * (sqrt(1.0 + alpha * alpha * t2) - 1.0);
}
float ggx_reflection(vec3 n, vec3 wo, vec3 wi, float eta, float alpha) {
    float co = dot(wo, n), ci = dot(wi, n);
    if (co == 0.0 || ci == 0.0 || !(co * ci > 0.0)) return 0.0;
    vec3 wm = wi + wo;
    if (!(dot(wm, wm) > 0.0)) return 0.0;
    wm = normalize(wm);
    if (dot(wm, n) < 0.0) wm = -wm;
    if (dot(wm, wi) * ci < 0.0 || dot(wm, wo) * co < 0.0) return 0.0;
    float cwo = dot(wo, wm);
    float F = cwo >= 0.0 ? fresnel_dielectric(cwo, eta) : fresnel_dielectric(-cwo, 1.0 / eta);
    float G = 1.0 / (1.0 + ggx_lambda(co, alpha) + ggx_lambda(ci, alpha));
    return ggx_D(dot(wm, n), alpha) * G * F / abs(4.0 * ci * co);
}

void main() {
    ivec2 gxy = ivec2(gl_FragCoord.xy);
    o_irradiance = o_specular = o_surface = o_translucency = vec4(0.0);
    ivec2 km = texelFetch(u_kind, gxy, 0).rg;
    int kind = km.x, mat = km.y;
    if (kind == 0) discard;
    ivec2 s = frame_sample(gxy);
    vec3 du = unnormalized_ray(s);
    vec3 p = du * texelFetch(u_view_z, gxy, 0).r;  // relative to the camera
    vec3 n = texelFetch(u_normal, gxy, 0).xyz;
    vec3 wo = kind == 2 ? -normalize(du) : -du;
    vec3 ns = kind == 1 && dot(n, wo) < 0.0 ? -n : n;
    int shape = texelFetch(u_shape, gxy, 0).r;
    // ShadowView::Projection::at of view k
    vec3 pc = vec3(0.0);
    if (u_views > 1) {
        // The receiver's cube face: the first view it projects into.
        int face = -1;
        for (int k = 0; k < u_views && face < 0; ++k) {
            vec3 a = p - u_origin_rel[k];
            vec3 c = vec3(dot(a, u_px[k]), dot(a, u_py[k]), dot(a, u_pw[k]));
            if (u_ortho || (c.z > 0.0 && abs(c.x) <= c.z && abs(c.y) <= c.z)) face = k;
        }
        if (face != u_view) discard;
    }
    // incident
    vec3 wi;
    vec3 E;
    if (u_directional) {
        wi = u_w;
        E = u_value;
    } else {
        vec3 d = u_pos_rel - p;
        float d2 = dot(d, d);
        if (!(d2 > 0.0)) discard;
        wi = d * (1.0 / sqrt(d2));
        float k = 1.0 / d2;
        if (u_lobe) {  // LightEmitter::factor
            float f = max(0.0, -dot(u_lobe_n, wi) * u_lobe_scale + u_lobe_offset);
            k *= u_lobe_squared ? min(1.0, f) * min(1.0, f) : f;
        }
        if (!(k > 0.0)) discard;
        E = u_value * k;
    }
    float cs = dot(ns, wi);
    vec3 a = p - u_origin_rel[u_view];
    if (u_need_map) pc = vec3(dot(a, u_px[u_view]), dot(a, u_py[u_view]), dot(a, u_pw[u_view]));
    vec4 m1 = material_row1(max(mat, 0));
    int slab_n = kind == 2 ? int(m1.w) : 0;
    // Thickness along the light's ray from the map's first hit, if that is the receiver's own
    // shape (ShadowMap::lookup, smooth).
    float d_thick = -1.0;
    if (kind == 2 && u_need_map && (u_thickness_view || (cs < 0.0 && slab_n > 0))) {
        float fx, fy;
        if (texel_coords(pc, fx, fy)) {
            int tx = int(fx), ty = int(fy);
            float map_depth = texelFetch(u_map_depth, map_texel(tx, ty), 0).r;
            int map_shape = texelFetch(u_map_shape, map_texel(tx, ty), 0).r;
            float smooth_depth = map_depth;
            float gx = fx - 0.5, gy = fy - 0.5;
            int x0 = int(floor(gx)), y0 = int(floor(gy));
            if (x0 >= 0 && y0 >= 0 && x0 + 1 < u_size && y0 + 1 < u_size) {
                float tx_ = gx - float(x0), ty_ = gy - float(y0);
                float v[4];
                bool ok = true;
                for (int k = 0; k < 4 && ok; ++k) {
                    ivec2 t = map_texel(x0 + k % 2, y0 + k / 2);
                    v[k] = texelFetch(u_map_depth, t, 0).r;
                    ok = texelFetch(u_map_shape, t, 0).r == map_shape && !isinf(v[k]);
                }
                if (ok)
                    smooth_depth = (v[0] * (1.0 - tx_) + v[1] * tx_) * (1.0 - ty_) +
                                   (v[2] * (1.0 - tx_) + v[3] * tx_) * ty_;
            }
            float per_depth = u_ortho ? 1.0 : length(a) / pc.z;
            if (map_shape == shape && !isinf(map_depth))
                d_thick = max(0.0, pc.z - smooth_depth) * per_depth;
        }
    }
    if (u_thickness_view) o_translucency.a = max(0.0, d_thick);
    if (!u_lights) return;
    if (cs > 0.0) {
        if (u_shadows) {
            float texel = u_texel * (u_ortho ? 1.0 : max(pc.z, 0.0));
            vec3 nl = dot(n, wi) >= 0.0 ? n : -n;
            float off = u_normal_offset * texel;
            vec3 dn = vec3(dot(nl, u_px[u_view]), dot(nl, u_py[u_view]), dot(nl, u_pw[u_view]));
            vec3 qc = pc + dn * off;
            float fx, fy;
            if (texel_coords(qc, fx, fy) &&
                !(qc.z <= texelFetch(u_map_depth, map_texel(int(fx), int(fy)), 0).r +
                               u_depth_bias * texel))
                return;  // shadowed (a return, not a discard: the thickness above is kept)
        }
        // Sphere lights in the way (not in the shadow maps).
        float dist = u_directional ? kInf : length(u_pos_rel - p);
        for (int k = 0; k < u_spheres; ++k)
            if (u_sphere_light[k] != u_light &&
                ray_sphere_hit(p, wi, u_sphere[k].xyz, u_sphere[k].w) < dist)
                return;
        if (kind == 1) {
            o_surface.rgb = m1.rgb * E * cs;
        } else {
            vec4 m0 = material_row0(mat);
            o_irradiance.rgb = boundary_T(mat, cs) * E * cs;
            if (m0.y > 0.0) o_specular.rgb = ggx_reflection(n, wo, wi, m0.x, m0.y) * cs * E;
        }
    } else if (kind == 2 && d_thick >= 0.0 && slab_n > 0) {
        o_translucency.rgb = E * (-cs) * slab_at(mat, slab_n, d_thick * u_unit_mm);
    }
}
