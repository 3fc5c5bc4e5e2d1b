// A shadow map of the GL lighting (realtime/gl/lighting_gl.h): ShadowView::to_clip in the vertex
// shader, positions relative to the camera. Perspective: (x, y, near, w), so that depth near / w
// is reversed as the G-buffer's (realtime/gl/raster_gl.h) and the clip volume's z >= 0 is the
// view's near plane; orthographic: w = 1 and z = 1 - depth / range (also reversed; the view's
// origin lies in front of every caster, so depth >= 0).
#version 330 core
layout(location = 0) in vec3 a_pos_rel;
uniform vec3 u_origin_rel, u_px, u_py, u_pw;
uniform bool u_ortho;
uniform float u_near, u_inv_range;
out float v_depth;
void main() {
    vec3 a = a_pos_rel - u_origin_rel;
    vec3 c = vec3(dot(a, u_px), dot(a, u_py), dot(a, u_pw));
    v_depth = c.z;
    gl_Position = u_ortho ? vec4(c.x, c.y, 1.0 - c.z * u_inv_range, 1.0)
                          : vec4(c.x, c.y, u_near, c.z);
}
