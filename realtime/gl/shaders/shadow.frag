// A shadow map of the GL lighting: depth of the first surface along the view's forward axis
// and its shape (ShadowMap::depth, ShadowMap::shape).
#version 330 core
uniform int u_shape;
in float v_depth;
layout(location = 0) out float o_depth;
layout(location = 1) out int o_shape;
void main() {
    o_depth = v_depth;
    o_shape = u_shape;
}
