// The separable screen-space SSS pass [Freude14 §4.2, Alg. 4.1; Jimenez et al. 2015], the GL twin
// of realtime/sss_pass.cpp, whose file comment (sss_pass.h) is the specification: the same taps,
// kernel scale (Eq. 4.11, from the centre pixel's view z), narrow-kernel rule, clamp-to-edge
// linear interpolation between two texels fetched by hand (a bilinear fetch would not apply the
// edge rule per texel), follow-surface (Eq. 4.12) or rejection per texel, tap jitter and the
// per-pixel rotation, with the same hashes. Arithmetic in float, in the CPU pass's order (even
// taps in one accumulator, odd in the other). Tap positions: PRECISE 1 (GLSL 4.00) computes them
// in double as the CPU pass does (offsets uploaded as two floats, hi + lo; the rotation's cosine
// and sine by a double polynomial), so that interpolation fractions are the CPU's to rounding;
// PRECISE 0 (GLSL 3.30) in float, the integer and fractional parts of the tap's offset in
// pixels taken apart, which costs up to ~1e-7 of the offset in pixels (see README "The GL
// twin": on sharp shadow edges that is 1e-4 of a dark pixel's value).
//
// One draw is one 1D pass of term u_term: PHASE 0 the first (along x, or the pixel's first
// rotated axis), writing R, G, B and the input's view z; PHASE 1 the second (along y, or the
// second axis), which adds the term with its signs to the sum of the earlier terms (u_prev).
// Variants by #define: MODE (0 none, 1 follow-surface, 2 reject), JITTER, ROTATE, PHASE, PRECISE.
//
// Textures (texelFetch only):
//   u_src   RGBA32F  R, G, B, view z: the G-buffer (phase 0) or phase 0's result (phase 1)
//   u_input RGBA32F  the G-buffer (R, G, B, view z): what pixels without the term keep
//   u_prev  RGBA32F  the sum of the earlier terms (phase 1, u_term > 0)
//   u_mat   R32I     material index, -1: no medium
//   u_taps  RGBA32F  texel (i, material * u_rank + term): offset_mm, weight R, G, B
//   u_jit   RGBA32F  texel (i, row): how far tap i may move left and right, mm; offset_mm's
//                    remainder (offset_mm - float(offset_mm))
//   u_meta  RGBA32F  texel (0, row): tap count (0: no such term), support_mm (hi, lo); (1, row): the
//                    weight sums R, G, B; (2, row): the signs R, G, B; (3, row): the weight
//                    sums' remainders (sum - float(sum))

uniform sampler2D u_src;
uniform sampler2D u_input;
uniform sampler2D u_prev;
uniform isampler2D u_mat;
uniform sampler2D u_taps;
uniform sampler2D u_jit;
uniform sampler2D u_meta;
uniform int u_term;
uniform int u_rank;
uniform ivec2 u_size;
#if PRECISE
#define POS double
uniform dvec2 u_per_mm_z;  // pixels per mm at view depth 1: x, y [Eq. 4.11]
#else
#define POS float
uniform vec2 u_per_mm_z;
#endif
uniform float u_follow;   // follow_strength / tan_half
uniform float u_reject;   // reject_depth
uniform uint u_seed;

out vec4 o_color;

// core/hash.h's hash32 (lowbias32) and approx::jitter_hash, bit for bit.
uint hash32(uint x) {
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}
float jitter_hash(int x, int y, int pass, int tap) {
    uint v = hash32(uint(x) * 0x9e3779b1u + 0x632be5abu + u_seed * 0x27d4eb2fu);
    v = hash32(v ^ (uint(y) * 0x85ebca77u));
    v = hash32(v ^ (uint(pass) * 0xc2b2ae3du + uint(tap)));
    return float(v >> 8) * (2.0 / 16777216.0) - 1.0;
}

// approx::tap_texels at the position pos + d along an axis of len texels (clamp-to-edge): the
// two texels and the weight t of the second. In float, d's integer and fractional parts are
// taken apart, so the fraction is as exact as d.
void tap_texels(int pos, POS d, int len, out int i0, out int i1, out float t) {
    POS s = POS(pos) + d;
    if (s <= POS(0)) {
        i0 = 0;
        t = 0.0;
    } else if (s >= POS(len - 1)) {
        i0 = len - 1;
        t = 0.0;
    } else {
#if PRECISE
        i0 = int(s);
        t = float(s - POS(i0));
#else
        float f = floor(d);
        i0 = pos + int(f);
        t = d - f;
#endif
    }
    i1 = min(i0 + 1, len - 1);
}

// Tap i's offset in mm (approx::jittered_offset_mm).
POS tap_offset(int row, int i, float o, int x, int y, int pass) {
    vec4 j = texelFetch(u_jit, ivec2(i, row), 0);
#if PRECISE
    POS off = POS(o) + POS(j.z);
#else
    POS off = o;
#endif
#if JITTER
    float xi = jitter_hash(x, y, pass, i);
    return off + POS(xi) * POS(xi < 0.0 ? j.x : j.y);
#else
    return off;
#endif
}

#if PRECISE && ROTATE
// cos and sin of a in [0, pi) to double precision (GLSL has no double trigonometry): b = a -
// pi / 2 in [-pi / 2, pi / 2), cos a = -sin b, sin a = cos b, Taylor series to b^21 and b^22
// (the remainders below 2e-18).
dvec2 cos_sin(double a) {
    double b = a - 1.5707963267948966LF, b2 = b * b;
    double s = 1.0LF, c = 1.0LF;
    for (int k = 21; k >= 3; k -= 2) s = 1.0LF - b2 / double(k * (k - 1)) * s;
    for (int k = 22; k >= 2; k -= 2) c = 1.0LF - b2 / double(k * (k - 1)) * c;
    return dvec2(-b * s, c);
}
#endif

// The edge rule for one texel of weight a (Eq. 4.12 or rejection); b collects the weight that
// goes to the centre (follow) or that was kept (reject).
void edge(inout float a, inout float b, inout bool dropped, vec4 v, int m, float zc, int mc) {
#if MODE == 0
    return;
#endif
#if MODE == 1
    float k = u_follow * abs(v.w - zc);
    float s = k < 1.0 ? k : 1.0;  // inf: 1
    b += a * s;
    a *= 1.0 - s;
#elif MODE == 2
    bool keep = m == mc && abs(v.w - zc) <= u_reject;
    dropped = dropped || (!keep && a != 0.0);
    a = keep ? a : 0.0;
    b += a;
#endif
}

// One output pixel of the 1D pass of this term at (x, y) along (ax, ay) pixels per mm.
// The term's weight sums per channel (in double where there is double: hi + lo).
#if PRECISE
#define WSUM dvec3
#else
#define WSUM vec3
#endif
WSUM weight_sum(int row) {
#if PRECISE
    return dvec3(texelFetch(u_meta, ivec2(1, row), 0).rgb) +
           dvec3(texelFetch(u_meta, ivec2(3, row), 0).rgb);
#else
    return texelFetch(u_meta, ivec2(1, row), 0).rgb;
#endif
}

#if PRECISE
#define AXIS dvec2
#else
#define AXIS vec2
#endif
vec3 filter_pixel(int x, int y, int row, AXIS axis, int pass, vec4 centre, int mc) {
    vec4 meta = texelFetch(u_meta, ivec2(0, row), 0);
    int count = int(meta.x);
    float zc = centre.w;
    vec3 acc[2] = vec3[2](vec3(0.0), vec3(0.0));
    vec3 extra[2] = vec3[2](vec3(0.0), vec3(0.0));
    bool dropped = false;
    for (int i = 0; i < count; ++i) {
        vec4 tap = texelFetch(u_taps, ivec2(i, row), 0);
        POS o = tap_offset(row, i, tap.x, x, y, pass);
        vec3 w = tap.yzw;
        int par = i & 1;
#if ROTATE
        int x0, x1, y0, y1;
        float fx, fy;
        tap_texels(x, o * axis.x, u_size.x, x0, x1, fx);
        tap_texels(y, o * axis.y, u_size.y, y0, y1, fy);
        ivec2 q[4] = ivec2[4](ivec2(x0, y0), ivec2(x1, y0), ivec2(x0, y1), ivec2(x1, y1));
        float a[4] = float[4]((1.0 - fx) * (1.0 - fy), fx * (1.0 - fy), (1.0 - fx) * fy, fx * fy);
        vec3 sum = vec3(0.0);
        float b = 0.0;
        for (int c = 0; c < 4; ++c) {
            vec4 v = texelFetch(u_src, q[c], 0);
            float wc = a[c];
            int m = MODE == 2 ? texelFetch(u_mat, q[c], 0).r : 0;
            edge(wc, b, dropped, v, m, zc, mc);
            sum += wc * v.rgb;
        }
        acc[0] += w * sum;
        extra[0] += w * b;
#else
        int i0, i1;
        float t;
        int pos = pass % 2 == 0 ? x : y;
        int len = pass % 2 == 0 ? u_size.x : u_size.y;
        tap_texels(pos, o * (pass % 2 == 0 ? axis.x : axis.y), len, i0, i1, t);
        ivec2 p0 = pass % 2 == 0 ? ivec2(i0, y) : ivec2(x, i0);
        ivec2 p1 = pass % 2 == 0 ? ivec2(i1, y) : ivec2(x, i1);
        vec4 v0 = texelFetch(u_src, p0, 0), v1 = texelFetch(u_src, p1, 0);
        float a1 = t, a0 = 1.0 - a1, b = 0.0;
#if MODE == 1
        // [Freude14 Eq. 4.12] as the CPU pass sums it: b = a0 s0 + a1 s1, then a *= 1 - s.
        float k0 = u_follow * abs(v0.w - zc), k1 = u_follow * abs(v1.w - zc);
        float s0 = k0 < 1.0 ? k0 : 1.0, s1 = k1 < 1.0 ? k1 : 1.0;
        b = a0 * s0 + a1 * s1;
        a0 *= 1.0 - s0;
        a1 *= 1.0 - s1;
#elif MODE == 2
        bool keep0 = texelFetch(u_mat, p0, 0).r == mc && abs(v0.w - zc) <= u_reject;
        bool keep1 = texelFetch(u_mat, p1, 0).r == mc && abs(v1.w - zc) <= u_reject;
        dropped = dropped || (!keep0 && a0 != 0.0) || (!keep1 && a1 != 0.0);
        a0 = keep0 ? a0 : 0.0;
        a1 = keep1 ? a1 : 0.0;
        b = a0 + a1;
#endif
        acc[par] += w * (a0 * v0.rgb + a1 * v1.rgb);
        extra[par] += w * b;
#endif
    }
    vec3 out_v = acc[0] + acc[1];
    vec3 kept = extra[0] + extra[1];
#if MODE == 1
    out_v += kept * centre.rgb;
#elif MODE == 2
    if (dropped) {
        // Each channel's sum rescaled by (all weights) / (kept weights), as the CPU pass does
        // it (in double where there is double).
        WSUM wsum = weight_sum(row);
        for (int ch = 0; ch < 3; ++ch)
            out_v[ch] = kept[ch] != 0.0 ? float(POS(out_v[ch]) * (wsum[ch] / POS(kept[ch])))
                                        : float(wsum[ch] * POS(centre[ch]));
    }
#endif
    return out_v;
}

void main() {
    ivec2 px = ivec2(gl_FragCoord.xy);
    int x = px.x, y = px.y;
    vec4 centre = texelFetch(u_src, px, 0);
    int m = texelFetch(u_mat, px, 0).r;
    int row = m * u_rank + u_term;
    bool has_term = m >= 0 && texelFetch(u_meta, ivec2(0, max(row, 0)), 0).x > 0.0;
#if PHASE == 1
    vec3 prev = u_term > 0 ? texelFetch(u_prev, px, 0).rgb : vec3(0.0);
    if (m < 0) {  // no medium: the input passes through
        o_color = vec4(texelFetch(u_input, px, 0).rgb, 0.0);
        return;
    }
    if (!has_term) {  // a lower-rank material: its sum so far (term 0: the empty sum)
        o_color = vec4(prev, 0.0);
        return;
    }
#else
    if (!has_term) {  // held between the passes
        o_color = centre;
        return;
    }
#endif
    // Kernel scale [Eq. 4.11] from the centre pixel's depth; the axis of this pass in pixels per
    // mm (rotated: (cos a, sin a) or (-sin a, cos a) on the medium's plane).
    AXIS scale = u_per_mm_z / POS(centre.w);
#if ROTATE
#if PRECISE
    dvec2 cs = cos_sin(1.5707963267948966LF * (double(jitter_hash(x, y, -1, -1)) + 1.0LF));
    double ca = cs.x, sa = cs.y;
#else
    float ang = 1.5707963267948966 * (jitter_hash(x, y, -1, -1) + 1.0);
    float ca = cos(ang), sa = sin(ang);
#endif
    AXIS axis = PHASE == 0 ? AXIS(ca * scale.x, sa * scale.y) : AXIS(-sa * scale.x, ca * scale.y);
    POS reach = max(abs(axis.x), abs(axis.y));
#else
    AXIS axis = scale;
    POS reach = PHASE == 0 ? scale.x : scale.y;
#endif
    vec4 meta = texelFetch(u_meta, ivec2(0, row), 0);
    vec3 v;
#if PRECISE
    POS support = POS(meta.y) + POS(meta.z);
#else
    POS support = meta.y;
#endif
    if (support * reach < POS(0.5)) {
        // The whole kernel within the centre pixel's bin: the identity times its mass.
        v = vec3(weight_sum(row) * WSUM(centre.rgb));
    } else {
        v = filter_pixel(x, y, row, axis, 2 * u_term + PHASE, centre, m);
    }
#if PHASE == 1
    vec3 sgn = texelFetch(u_meta, ivec2(2, row), 0).rgb;
    o_color = vec4(u_term > 0 ? prev + sgn * v : sgn * v, 0.0);
#else
    o_color = vec4(v, centre.w);
#endif
}
