/* The shading frame at a hit, in which the BSDFs see directions (kernels/bsdf.cl): z the
 * shading normal, x the tangent. Isotropic BSDFs do not care how the tangent turns about the
 * normal, so a program whose materials are all isotropic builds the frame from the normal alone
 * (make_frame) each time it needs it. One with anisotropic roughness (ANISOTROPIC, the
 * roughness along x and y apart) follows Mitsuba 3's convention: x is dp/du made orthogonal to
 * the shading normal (SurfaceInteraction::initialize_sh_frame), kept in the Surface. */

/* Derivatives found in the space of surface s's object, turned to the world's (a program
 * without instances has them there already). */
void instanced_derivatives(const SceneData *sc, const Surface *s, float3 *dpdu, float3 *dpdv)
{
#ifdef INSTANCES
    if (!INSTANCED(s->instance))
        return;
    const global float4 *m = sc->instances[s->instance].to_world;
    *dpdu = transform_vector(m, *dpdu);
    *dpdv = transform_vector(m, *dpdv);
#endif
}

/* dp/du and dp/dv at a hit: a triangle's from its corners' texture coordinates (pbrt-v4
 * eq. 6.7), or, where those are missing or degenerate, its edges from v0, the derivatives of the
 * barycentric parameterisation (u, v) = (b1, b2) that Mitsuba 3.9 gives a mesh without texture
 * coordinates (read off its SurfaceInteraction: dp_du = v1 - v0); a sphere's as Mitsuba's
 * sphere gives them for its (u, v) = (phi / 2 pi, theta / pi). An instance's triangle has its
 * object's, turned to the world (instanced_derivatives). */
void surface_derivatives(const SceneData *sc, const Surface *s, float3 *dpdu, float3 *dpdv)
{
#ifndef NO_TRIANGLES
    if (s->prim >= sc->num_spheres) {
        const global Triangle *tri = &sc->triangles[s->prim - sc->num_spheres];
#ifdef SHAPES
        if (SHAPE_KIND(tri)) {
            float3 p = s->p;
#ifdef INSTANCES
            if (INSTANCED(s->instance))
                p = transform_point(sc->instances[s->instance].to_object, p);
#endif
            analytic_derivatives(SHAPE_KIND(tri), SHAPE_ROWS(sc, tri), p, dpdu, dpdv);
            instanced_derivatives(sc, s, dpdu, dpdv);
            return;
        }
#endif
        int k = as_int(tri->v1.w);
        if (k >= 0) {
            float2 duv02 = sc->uvs[k] - sc->uvs[k + 2], duv12 = sc->uvs[k + 1] - sc->uvs[k + 2];
            float3 dp02 = tri->v0.xyz - tri->v2.xyz, dp12 = tri->v1.xyz - tri->v2.xyz;
            float det = duv02.x * duv12.y - duv02.y * duv12.x;
            if (fabs(det) > 1e-12f) {
                *dpdu = (duv12.y * dp02 - duv02.y * dp12) / det;
                *dpdv = (duv02.x * dp12 - duv12.x * dp02) / det;
                instanced_derivatives(sc, s, dpdu, dpdv);
                return;
            }
        }
        *dpdu = tri->v1.xyz - tri->v0.xyz;
        *dpdv = tri->v2.xyz - tri->v0.xyz;
        instanced_derivatives(sc, s, dpdu, dpdv);
        return;
    }
#endif
    Sphere sphere = sc->spheres[s->prim];
    float3 l = (s->p - sphere.xyz) / sphere.w;
    float rd = sqrt(l.x * l.x + l.y * l.y);
    float2 phi = rd > 0.0f ? (float2)(l.x, l.y) / rd : (float2)(1.0f, 0.0f);
    *dpdu = 2.0f * PI_F * sphere.w * (float3)(-l.y, l.x, 0.0f);
    *dpdv = PI_F * sphere.w * (float3)(l.z * phi.x, l.z * phi.y, -rd);
}

/* The unit tangent of s's shading frame: dp/du without its part along the shading normal n, or
 * make_frame's where dp/du is parallel to n (a sphere's pole). */
float3 shading_tangent(const SceneData *sc, const Surface *s)
{
    float3 dpdu, dpdv, n = s->ns;
    surface_derivatives(sc, s, &dpdu, &dpdv);
    float3 t = dpdu - n * dot(n, dpdu);
    float len = length(t);
    if (len > 0.0f && isfinite(len))
        return t / len;
    make_frame(n, &t, &dpdv);
    return t;
}

/* Completes s's shading frame once its normal is final (after a normal map): a program with
 * anisotropic materials keeps the tangent; others need nothing. */
void complete_frame(const SceneData *sc, Surface *s)
{
#ifdef ANISOTROPIC
    s->ts = shading_tangent(sc, s);
#endif
}

/* World direction v in s's shading frame, and back. */
float3 to_shading(const Surface *s, float3 v)
{
#ifdef ANISOTROPIC
    float3 b = cross(s->ns, s->ts);
    return (float3)(dot(v, s->ts), dot(v, b), dot(v, s->ns));
#else
    return to_frame(v, s->ns);
#endif
}

float3 from_shading(const Surface *s, float3 v)
{
#ifdef ANISOTROPIC
    return v.x * s->ts + v.y * cross(s->ns, s->ts) + v.z * s->ns;
#else
    return to_world(v, s->ns);
#endif
}
