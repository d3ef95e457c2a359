//! Proptest strategies shared by `tests/properties.rs` (the reference) and
//! `tests/vulkan_properties.rs` (every backend).

use proptest::prelude::*;

/// Random legal material as TOML: every model, distribution, G, F and convention, with
/// illegal combinations steered to legal ones (Smith needs Beckmann/GGX, smith-fast needs
/// Beckmann, anisotropy needs the modern convention).
pub fn material_toml() -> impl Strategy<Value = String> {
    let choice = (
        0usize..6,
        0usize..4,
        0usize..5,
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
                    let d = ["gaussian", "beckmann", "ggx", "blinn"][dist];
                    let param = match d {
                        "gaussian" => format!("roughness = {mx:?}"),
                        "blinn" => format!("exponent = {e:?}"),
                        _ => r,
                    };
                    let aniso = param.contains('[');
                    let conv = if aniso { "modern" } else { ["seed", "cook-torrance-1982", "modern"][conv] };
                    let mut g = ["none", "cook-torrance", "smith", "smith-correlated", "smith-fast"][geom];
                    if matches!(d, "gaussian" | "blinn") && g.starts_with("smith") {
                        g = "cook-torrance";
                    }
                    if d == "ggx" && g == "smith-fast" {
                        g = "smith";
                    }
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
