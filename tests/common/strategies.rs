//! Proptest strategies shared by `tests/properties.rs` (the reference) and
//! `tests/vulkan_properties.rs` (every backend).

use proptest::prelude::*;
use vkbrdf::material::{legality, Convention, DistributionKind, Geometry};

/// The first legal one of: the combination as drawn, in the modern convention, isotropic,
/// with G = cook-torrance (legal with every isotropic distribution).
fn steer(
    conv: Convention,
    kind: DistributionKind,
    aniso: bool,
    g: Geometry,
) -> (Convention, bool, Geometry) {
    [
        (conv, aniso, g),
        (Convention::Modern, aniso, g),
        (conv, false, g),
        (conv, false, Geometry::CookTorrance),
    ]
    .into_iter()
    .find(|&(c, a, g)| legality(c, kind, a, g).is_ok())
    .expect("cook-torrance is legal with every isotropic distribution")
}

/// Random legal material as TOML: every model, distribution, G, F and convention, with
/// illegal combinations steered to legal ones by `material::legality` (the one statement
/// of the rules): first the modern convention, then isotropic roughness, then G =
/// cook-torrance, until the combination is legal.
pub fn material_toml() -> impl Strategy<Value = String> {
    let choice = (
        0usize..6,
        0usize..DistributionKind::ALL.len(),
        0usize..Geometry::ALL.len(),
        0usize..4,
        0usize..3,
        any::<bool>(),
    );
    let exponent = prop_oneof![0.0..5.0f64, 5.0..200.0f64, 200.0..1e4f64];
    let roughness = (0.01..2.0f64, 0.01..2.0f64);
    let rgb = || prop::array::uniform3(0.0..1.0f64);
    let optics = (
        prop::array::uniform3(0.05..5.0f64),
        prop::array::uniform3(0.0..10.0f64),
        rgb(),
    );
    let weights = (rgb(), rgb(), 0.0..1.0f64, 0.0..1.0f64);
    (choice, exponent, roughness, optics, weights).prop_map(
        |((model, dist, geom, fres, conv, aniso), e, (mx, my), (ior, ext, f0), w)| {
            let (diffuse, specular, dw, sw) = w;
            let mut t = format!("diffuse = {diffuse:?}\n");
            let r = if aniso {
                format!("roughness = [{mx:?}, {my:?}]")
            } else {
                format!("roughness = {mx:?}")
            };
            let body = match model {
                0 => "model = \"lambert\"".to_string(),
                1 => format!("model = \"phong\"\nexponent = {e:?}"),
                2 => format!("model = \"blinn-phong\"\nexponent = {e:?}"),
                3 => format!("model = \"rtr\"\nexponent = {e:?}"),
                4 => format!("model = \"ward\"\n{r}"),
                _ => {
                    let kind = DistributionKind::ALL[dist];
                    let (conv, aniso, g) = steer(
                        Convention::ALL[conv],
                        kind,
                        aniso && !kind.takes_exponent(),
                        Geometry::ALL[geom],
                    );
                    let max = kind.max_roughness().unwrap_or(f64::INFINITY);
                    let param = if kind.takes_exponent() {
                        format!("exponent = {e:?}")
                    } else if aniso {
                        r
                    } else {
                        format!("roughness = {:?}", mx.min(max))
                    };
                    let (d, conv, g) = (kind.toml_name(), conv.toml_name(), g.toml_name());
                    let f = match fres {
                        0 => "fresnel = \"none\"".to_string(),
                        1 => format!("fresnel = \"dielectric\"\nior = {ior:?}"),
                        2 => format!("fresnel = \"conductor\"\nior = {ior:?}\nextinction = {ext:?}"),
                        _ => format!("fresnel = \"schlick\"\nf0 = {f0:?}"),
                    };
                    format!(
                        "model = \"cook-torrance\"\nconvention = \"{conv}\"\ndistribution = \"{d}\"\n{param}\ngeometry = \"{g}\"\n{f}\ndiffuse_weight = {dw:?}\nspecular_weight = {sw:?}"
                    )
                }
            };
            if model != 0 {
                t += &format!("specular = {specular:?}\n");
            }
            t + &body
        },
    )
}

/// A finite direction of random length in 1e-20 … 1e20 (zero only with probability 0).
pub fn direction() -> impl Strategy<Value = [f64; 3]> {
    (prop::array::uniform3(-1.0..1.0f64), -20.0..20.0f64)
        .prop_map(|(d, p)| d.map(|x| x * 10f64.powf(p)))
}
