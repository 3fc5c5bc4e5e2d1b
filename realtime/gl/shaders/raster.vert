// The G-buffer's geometry (realtime/gl/raster_gl.h): clip coordinates come from the CPU
// (RasterCamera::to_clip in double: x, y, w) with z = near, so that the depth z / w = near / w is
// reversed (1 at the near plane, towards 0 far away).
#version 330 core
layout(location = 0) in vec4 a_clip;
void main() {
    gl_Position = a_clip;
}
