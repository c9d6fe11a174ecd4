#version 330 core
// A full-window triangle pair; uv (0, 0) is the image's top-left pixel.
in vec2 position;
out vec2 uv;
void main()
{
    uv = vec2(position.x * 0.5 + 0.5, 0.5 - position.y * 0.5);
    gl_Position = vec4(position, 0.0, 1.0);
}
