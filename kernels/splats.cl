/* Light tracing's splats (kernels/bdpt.cl: strategies t = 1): contributions that land at a film
 * point of their own, wherever it is, added to a per-launch film by atomics and added to the
 * pixels' sums after the launch (add_splats). */

/* Adds v to *a. OpenCL 1.2 has no atomic float add, so elsewhere it is a compare-and-swap loop
 * on its bits; on NVIDIA's OpenCL it is PTX's reduction, which the thread does not wait for,
 * where each attempt of the loop waits for a load and an atomic's round trip: on an H200 the
 * loop took 60 % of BDPT's time (docs/notes/performance-2026-11.md, 2026-11-30). */
void atomic_add_float(volatile global float *a, float v)
{
#ifdef NVIDIA_PTX
    asm volatile("red.global.add.f32 [%0], %1;" :: "l"(a), "f"(v) : "memory");
#else
    volatile global uint *bits = (volatile global uint *)a;
    uint old = *bits, seen;
    while ((seen = atomic_cmpxchg(bits, old, as_uint(as_float(old) + v))) != old)
        old = seen;
#endif
}

/* Adds contribution c of film point `at` (pixels) to the splat film, to every pixel whose filter
 * reaches the point, weighted by the density with which that pixel's camera rays land there
 * (filter importance sampling, kernels/camera.cl: pdf_filter along each axis): a light-traced
 * point counts for each pixel as its camera rays would. */
void splat(global float4 *film, const RenderParams *p, float2 at, float3 c)
{
    float r = p->filter.x;
    int x0 = max((int)ceil(at.x - r - 0.5f), 0), x1 = min((int)floor(at.x + r - 0.5f), (int)p->width - 1);
    int y0 = max((int)ceil(at.y - r - 0.5f), 0), y1 = min((int)floor(at.y + r - 0.5f), (int)p->height - 1);
    for (int y = y0; y <= y1; ++y) {
        float wy = pdf_filter(p, at.y - ((float)y + 0.5f));
        for (int x = x0; x <= x1; ++x) {
            float w = wy * pdf_filter(p, at.x - ((float)x + 0.5f));
            if (!(w > 0.0f))
                continue;
            volatile global float *px = (volatile global float *)&film[y * p->width + x];
            atomic_add_float(px, w * c.x);
            atomic_add_float(px + 1, w * c.y);
            atomic_add_float(px + 2, w * c.z);
        }
    }
}
