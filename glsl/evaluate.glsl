// evaluate.glsl — one tuple's model, chosen by the material's code: the dispatch over the
// models of models.glsl and htsg.glsl (measured materials read their table in
// measured.glsl instead).

#ifndef VKBRDF_EVALUATE_GLSL
#define VKBRDF_EVALUATE_GLSL

#include "frame_fields.glsl"
#include "material.glsl"
#include "models.glsl"
#include "htsg.glsl"

// The model of material m at frame f (a valid, above-horizon tuple).
Eval evaluate(Frame f, GpuMaterial m) {
    switch (material_model(m)) {
#if defined(HAS_LAMBERT)
    case MODEL_LAMBERT: return model_lambert(m);
#endif
#if defined(HAS_PHONG)
    case MODEL_PHONG: return model_phong(f, m);
#endif
#if defined(HAS_BLINN_PHONG)
    case MODEL_BLINN_PHONG: return model_blinn_phong(f, m);
#endif
#if defined(HAS_RTR)
    case MODEL_RTR: return model_rtr(f, m);
#endif
#if defined(HAS_WARD)
    case MODEL_WARD: return model_ward(f, m);
#endif
#if defined(HAS_COOK_TORRANCE)
    case MODEL_COOK_TORRANCE: return model_cook_torrance(f, m);
#endif
#if defined(HAS_HTSG)
    case MODEL_HTSG: return model_htsg(f, m);
#endif
    default: return eval_zero();
    }
}

#endif
