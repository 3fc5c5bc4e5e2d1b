// The G-buffer's geometry (realtime/gl/raster_gl.h): view depth, shape and triangle per sample.
#version 330 core
uniform int u_shape;
layout(location = 0) out float o_view_z;
layout(location = 1) out int o_shape;
layout(location = 2) out int o_triangle;
void main() {
    o_view_z = 1.0 / gl_FragCoord.w;  // w_clip is the view depth (RasterCamera::to_clip)
    o_shape = u_shape;
    o_triangle = gl_PrimitiveID;
}
