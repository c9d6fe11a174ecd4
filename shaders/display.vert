#version 330 core
// The image as a quad centred in the window, covering `extent` of it (the image keeps its aspect
// ratio: the rest is bars); uv (0, 0) is the image's top-left pixel.
uniform vec2 extent;
in vec2 position;
out vec2 uv;
void main()
{
    uv = vec2(position.x * 0.5 + 0.5, 0.5 - position.y * 0.5);
    gl_Position = vec4(position * extent, 0.0, 1.0);
}
