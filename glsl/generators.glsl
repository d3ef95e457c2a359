// generators.glsl — directions made on the device instead of read: the half/difference
// slice's texels (GENERATE_HALF_DIFF) and the importance-sampled half vectors of the
// albedo/DFG integrals (GENERATE_IMPORTANCE, summed by integrators.glsl), with the f32
// sin/cos polynomials they share.

#ifndef VKBRDF_GENERATORS_GLSL
#define VKBRDF_GENERATORS_GLSL

#include "math.glsl"
#include "bindings.glsl"
#include "input.glsl"

#if defined(GENERATE_HALF_DIFF) || defined(GENERATE_IMPORTANCE)

// Texel `g` of the half/difference slice (src/table/slice.rs, Rusinkiewicz 1998), made on
// the device instead of read: column i -> x = (i + 1/2)/W, theta_h = x^2 pi/2 (or x pi/2);
// row j -> theta_d = (j + 1/2)/H pi/2; phi_d = 90 degrees, phi_h = 0, n = +z, material 0,
// tangent +x. With phi_d = 90 degrees, d = (0, sin theta_d, cos theta_d), l = R_y(theta_h) d
// and v is l reflected about h = (sin theta_h, 0, cos theta_h): the host's from_half_diff()
// term for term. No tuple is loaded: on lavapipe the loads are about half of the
// kernel's time (see docs/THROUGHPUT.md).
// sin(t pi/2) and cos(t pi/2) for t in [0, 1/2], i.e. angles up to pi/4, by their Taylor
// polynomials to x^11 and x^12: the first omitted terms are below (pi/4)^13/13! = 7e-12
// and (pi/4)^14/14! = 4e-13 relative to the results, so the polynomials are as exact as f32.
vec2 sin_cos_eighth(float t) {
    float x = t * (0.5 * PI);
    float x2 = x * x;
    float s = x * (1.0 - x2 / 6.0 * (1.0 - x2 / 20.0 * (1.0 - x2 / 42.0 * (1.0 - x2 / 72.0
              * (1.0 - x2 / 110.0)))));
    float c = 1.0 - x2 / 2.0 * (1.0 - x2 / 12.0 * (1.0 - x2 / 30.0 * (1.0 - x2 / 56.0
              * (1.0 - x2 / 90.0 * (1.0 - x2 / 132.0)))));
    return vec2(s, c);
}

// (sin, cos) of theta = u pi/2 for u in [0, 1], given also ubar = 1 - u computed without
// cancellation. Above pi/4 the complement is used (sin theta = cos(ubar pi/2)): forming
// theta, or pi/2 - theta, in f32 would leave ~1e-7 absolute error in the small cosine of
// a grazing angle, where the host's f64 angle has none (measured: 1.5e-5 relative in the
// slice against 7e-6 this way). Neither a range reduction nor the built-in sin/cos (which
// reduce the argument first) is needed.
vec2 sin_cos_quadrant(float u, float ubar) {
    return u <= 0.5 ? sin_cos_eighth(u) : sin_cos_eighth(ubar).yx;
}

// g / w, without an integer division (x86 has no vector one: llvmpipe would divide lane
// by lane): g < 2^24 (MAX_GENERATED_TEXELS on the host) is exact in f32, so the rounded
// quotient is within one of the true one, and the correction makes it exact.
uint quotient(uint g, uint w) {
    uint j = uint(float(g) / float(w));
    return j * w > g ? j - 1u : ((j + 1u) * w <= g ? j + 1u : j);
}

Row half_diff_row(uint g) {
    uint w = params.grid_width;
    uint j = quotient(g, w);
    uint i = g - j * w;
    // Column and row centres x = (i + 1/2)/W, y = (j + 1/2)/H and their complements, each
    // one rounding.
    float fw = float(w), fh = float(params.grid_height);
    float x = (float(i) + 0.5) / fw;
    float xbar = (fw - float(i) - 0.5) / fw;
    float y = (float(j) + 0.5) / fh;
    float ybar = (fh - float(j) - 0.5) / fh;
    // theta_h = u pi/2 with u = x (linear) or x^2 (MERL), 1 - x^2 = (1 - x)(1 + x).
    bool linear = params.spacing != 0u;
    vec2 h = sin_cos_quadrant(linear ? x : x * x, linear ? xbar : xbar * (1.0 + x));
    vec2 d = sin_cos_quadrant(y, ybar);
    Row r;
    r.l = vec3(d.y * h.x, d.x, d.y * h.y);
    float lh = r.l.x * h.x + r.l.z * h.y; // = cos theta_d
    r.v = 2.0 * lh * vec3(h.x, 0.0, h.y) - r.l;
    r.n = vec3(0.0, 0.0, 1.0);
    r.material = 0.0;
    r.t = vec3(1.0, 0.0, 0.0);
    set_bits(r);
    return r;
}
#endif

#if defined(GENERATE_IMPORTANCE)
// (sin, cos) of 2 pi u for u in [0, 1): the quadrant q = floor(4u) by exact f32
// arithmetic, the rest by sin_cos_quadrant.
vec2 sin_cos_turn(float u) {
    float q = floor(4.0 * u);
    float t = 4.0 * u - q; // exact: 4u is exact and q is its integer part
    vec2 sc = sin_cos_quadrant(t, 1.0 - t);
    return q == 0.0 ? sc : q == 1.0 ? vec2(sc.y, -sc.x) : q == 2.0 ? -sc : vec2(-sc.y, sc.x);
}

// Hammersley point k of n: ((k + 1/2)/n, radical inverse of k).
vec2 hammersley(uint k, uint n) {
    float u1 = (float(k) + 0.5) / float(n);
    float u2 = float(bitfieldReverse(k)) * (1.0 / 4294967296.0);
    return vec2(u1, u2);
}

// The half vector h of the sample u (a Hammersley point) in the local frame (n = +z) of
// one (mu, alpha) point of src/table/albedo.rs: GGX by its visible normals (Heitz 2018;
// t1, t2, t3 = v_h and s are the host's constants of that point), or Beckmann by D cos_h.
// The caller drops a degenerate h (l below the horizon or NaN).
vec3 importance_half_vector(vec2 u, bool ggx, vec3 t1, vec3 t2, vec3 t3, float s, float alpha) {
    float u1 = u.x;
    vec2 phi = sin_cos_turn(u.y); // (sin, cos)
    vec3 h;
    if (ggx) {
        // Heitz 2018, "Sampling the GGX Distribution of Visible Normals", listing 1.
        float r = sqrt(u1);
        float p1 = r * phi.y;
        float p2 = (1.0 - s) * sqrt(max(1.0 - p1 * p1, 0.0)) + s * r * phi.x;
        float p3 = sqrt(max(1.0 - p1 * p1 - p2 * p2, 0.0));
        vec3 nh = p1 * t1 + p2 * t2 + p3 * t3;
        h = normalize(vec3(alpha * nh.x, alpha * nh.y, max(nh.z, 0.0)));
    } else {
        // D cos_h: tan^2 = -alpha^2 ln(1 - u1), by log1p (u1 is as small as 1/(2n)).
        float tan2 = alpha * alpha * -log1p_acc(-u1);
        float cos_t = inversesqrt(1.0 + tan2);
        float sin_t = sqrt(tan2) * cos_t;
        h = vec3(sin_t * phi.y, sin_t * phi.x, cos_t);
    }
    return h;
}
#endif

#endif
