// measured.glsl — measured (MERL) materials: the half/difference lookup of
// src/material/merl.rs (FORMULAS.md §7, "MERL lookup"), nearest-bin or linear, in the
// batch's MERL tables (BINDING_MERL: per table, R, G, B blocks of f in 1/sr, f32, in MERL's
// bin order; a material's kind.y is its table, kind.z its lookup).

#ifndef VKBRDF_MEASURED_GLSL
#define VKBRDF_MEASURED_GLSL

#include "material.glsl"
#include "input.glsl"
#include "frame64.glsl"
#include "models.glsl"

layout(std430, set = 0, binding = BINDING_MERL) readonly buffer Merl {
    float merl[];
};

const uint MERL_SAMPLES = 90u * 90u * 180u;
// BIN_TOLERANCE of src/material/merl.rs: a coordinate within 1/1000 of a bin below its
// lower edge counts as in that bin (the bins' own sample points find their bin).
const float MERL_BIN_TOLERANCE = 1e-3;

// f of channel c of table `table` at bin (i, j, k).
float merl_value(uint table, uint c, uint i, uint j, uint k) {
    return merl[(3u * table + c) * MERL_SAMPLES + k + 180u * (j + 90u * i)];
}

vec3 merl_rgb(uint table, uint i, uint j, uint k) {
    return vec3(merl_value(table, 0u, i, j, k), merl_value(table, 1u, i, j, k),
                merl_value(table, 2u, i, j, k));
}

#if !defined(HAS_FLOAT64)
// Never dispatched: the host refuses measured materials on a device without f64
// (src/gpu/evaluator.rs, upload_measured), since an f32 atan2 cannot choose the reference's
// bin. The variant still compiles (every feature set does), and reads as 0.
Eval model_measured(Row r, GpuMaterial m) {
    return eval_zero();
}
#else

const double PI64 = 3.14159265358979323846LF;

// (sin x, cos x) for |x| <= pi to ~1e-16: Taylor series of x/2 to order 21 (its first
// omitted term is below 3e-16 at x/2 = pi/2), then the double-angle formulas.
dvec2 sin_cos64(double x) {
    double h = 0.5 * x, h2 = h * h;
    double s = 1.0LF, c = 1.0LF;
    for (int k = 10; k >= 1; --k) {
        s = 1.0LF - h2 / double((2 * k) * (2 * k + 1)) * s;
        c = 1.0LF - h2 / double((2 * k - 1) * (2 * k)) * c;
    }
    s *= h;
    return dvec2(2.0LF * s * c, c * c - s * s);
}

// atan2(y, x) in f64 (GLSL has no f64 atan): the f32 angle a, corrected by the angle that
// remains after rotating (x, y) by -a, r = atan(tan(remainder)) ~ t - t^3/3 with |t| ~ 1e-7.
// 0 for (0, 0), as the reference's atan2 (its signed zeros aside, which fold to bin 0).
double atan2_64(double y, double x) {
    if (x == 0.0LF && y == 0.0LF) {
        return 0.0LF;
    }
    double a = double(atan(float(y), float(x)));
    dvec2 sc = sin_cos64(a);
    double t = (y * sc.y - x * sc.x) / (x * sc.y + y * sc.x);
    return a + t - t * t * t / 3.0LF;
}

// MERL's continuous bin coordinates of the tuple: (sqrt(theta_h/(pi/2)) 90,
// theta_d/(pi/2) 90, (phi_d mod pi)/pi 180), sample points at the integers. The half and
// difference frame is built as the reference builds it (b = n x h normalised, or n x x,
// n x y when h = n; t = b x h; d = l in (t, b, h)), all of it in f64 from the exact
// inputs, atan2 included (atan2_64): the bin and the weights are then the reference's (an
// f32 frame and atan2 put 1 in 10^4 tuples in the neighbouring bin, 2-10 % off, and made
// the linear weights 1e-5 off: 5e-4 relative in f on a glossy lobe).
dvec3 merl_coordinates(Row r) {
    dvec3 n = unit64(r.n_bits), l = unit64(r.l_bits), v = unit64(r.v_bits);
    dvec3 lv = l + v;
    dvec3 h = lv / sqrt(dot(lv, lv));
    dvec3 nxh = cross(n, h);
    double s2 = dot(nxh, nxh);
    dvec3 b = cross(n, dvec3(1.0, 0.0, 0.0));
    if (s2 > 0.0) {
        b = nxh;
    } else if (dot(b, b) == 0.0) {
        b = cross(n, dvec3(0.0, 1.0, 0.0));
    }
    b = b / sqrt(dot(b, b));
    dvec3 t = cross(b, h);
    dvec3 d = dvec3(dot(l, t), dot(l, b), dot(l, h));
    double theta_h = atan2_64(sqrt(s2), dot(n, h));
    double theta_d = atan2_64(sqrt(d.x * d.x + d.y * d.y), d.z);
    double phi_d = atan2_64(d.y, d.x);
    double half_pi = 0.5LF * PI64;
    // phi_d mod pi: reciprocity maps phi_d + pi to phi_d.
    if (phi_d < 0.0) {
        phi_d += 2.0 * half_pi;
    }
    if (phi_d >= 2.0 * half_pi) {
        phi_d -= 2.0 * half_pi;
    }
    return dvec3(sqrt(max(theta_h, double(0.0)) / half_pi) * 90.0,
                    max(theta_d, double(0.0)) / half_pi * 90.0,
                    phi_d / (2.0 * half_pi) * 180.0);
}

// FORMULAS.md §7: f of a measured material; D = 0, G = F = K = 1 (no decomposition).
Eval model_measured(Row r, GpuMaterial m) {
    dvec3 x = merl_coordinates(r);
    uint table = material_merl_table(m);
    vec3 rgb;
    if (material_merl_lookup(m) == LOOKUP_LINEAR) {
        // Trilinear between sample points; theta_h, theta_d hold index 89 beyond it,
        // phi_d wraps (180 = 0).
        dvec3 c = dvec3(min(x.x, double(89.0)), min(x.y, double(89.0)), x.z);
        dvec3 lo = floor(c);
        vec3 w = vec3(c - lo);
        uint i0 = uint(lo.x), j0 = uint(lo.y), k0 = uint(lo.z) % 180u;
        uint i1 = min(i0 + 1u, 89u), j1 = min(j0 + 1u, 89u), k1 = (k0 + 1u) % 180u;
        vec3 c00 = mix(merl_rgb(table, i0, j0, k0), merl_rgb(table, i0, j0, k1), w.z);
        vec3 c01 = mix(merl_rgb(table, i0, j1, k0), merl_rgb(table, i0, j1, k1), w.z);
        vec3 c10 = mix(merl_rgb(table, i1, j0, k0), merl_rgb(table, i1, j0, k1), w.z);
        vec3 c11 = mix(merl_rgb(table, i1, j1, k0), merl_rgb(table, i1, j1, k1), w.z);
        rgb = mix(mix(c00, c01, w.y), mix(c10, c11, w.y), w.x);
    } else {
        // MERL's truncation, with the bin tolerance; clamped to the table.
        dvec3 idx = max(floor(x + double(MERL_BIN_TOLERANCE)), dvec3(0.0));
        uint i = x.x > 0.0 ? min(uint(idx.x), 89u) : 0u;
        uint j = min(uint(idx.y), 89u);
        uint k = uint(idx.z) % 180u;
        rgb = merl_rgb(table, i, j, k);
    }
    Eval e;
    e.brdf = rgb;
    e.d = 0.0;
    e.g = 1.0;
    e.f = vec3(1.0);
    e.k = 1.0;
    return e;
}
#endif

#endif
