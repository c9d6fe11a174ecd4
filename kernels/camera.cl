/* A pinhole camera. (sx, sy) is a point on the film in pixels, (0, 0) the top-left corner. */
float3 camera_direction(const RenderParams *p, float sx, float sy)
{
    float ndc_x = 2.0f * sx / p->width - 1.0f;
    float ndc_y = 1.0f - 2.0f * sy / p->height;
    return unit(p->forward.xyz + ndc_x * p->right.xyz + ndc_y * p->up.xyz);
}
