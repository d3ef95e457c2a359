//! The parameter space of a fit: which of a starting material's continuous parameters are
//! free (`--free`), their bounds, which enter f linearly (solved exactly per evaluation
//! for the L2 losses) and which the optimiser moves, and the material at a point.

use crate::error::{Error, Result};
use crate::material::{Distribution, Fresnel, Material, Model, Rgb, Roughness};

/// A named free parameter (`--free NAME,…`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Param {
    /// Roughness `m` (α): Cook–Torrance's Beckmann, GGX or Gaussian, Ward's.
    Roughness,
    /// Schlick's `F0` per channel.
    F0,
    /// The diffuse albedo per channel (`d · c_diff`).
    Diffuse,
    /// The specular albedo per channel (`s · c_spec`).
    Specular,
    /// A dielectric's η (one value) or a conductor's n (per channel).
    Ior,
    /// A conductor's k per channel.
    Extinction,
    /// The exponent of Phong, Blinn–Phong, RTR or the `blinn` distribution.
    Exponent,
}

impl Param {
    /// Every parameter, in the order `--help` lists them.
    pub const ALL: [Param; 7] = [
        Param::Roughness,
        Param::F0,
        Param::Diffuse,
        Param::Specular,
        Param::Ior,
        Param::Extinction,
        Param::Exponent,
    ];

    /// The name `--free` takes (the materials file's key).
    pub fn name(self) -> &'static str {
        match self {
            Param::Roughness => "roughness",
            Param::F0 => "f0",
            Param::Diffuse => "diffuse",
            Param::Specular => "specular",
            Param::Ior => "ior",
            Param::Extinction => "extinction",
            Param::Exponent => "exponent",
        }
    }

    /// The default bounds (docs/FITTING.md): roughness [1e-3, 1], F0 [0, 1], albedos
    /// [0, ∞), a dielectric's η [1, 3] or a conductor's n [0.01, 10], k [0, 20], an
    /// exponent [0, 1e6].
    pub fn default_bounds(self, conductor: bool) -> (f64, f64) {
        match self {
            Param::Roughness => (1e-3, 1.0),
            Param::F0 => (0.0, 1.0),
            Param::Diffuse | Param::Specular => (0.0, f64::INFINITY),
            Param::Ior if conductor => (0.01, 10.0),
            Param::Ior => (1.0, 3.0),
            Param::Extinction => (0.0, 20.0),
            Param::Exponent => (0.0, 1e6),
        }
    }

    /// Whether the parameter enters f linearly (per channel), so that the L2 losses
    /// solve it exactly instead of searching for it.
    pub fn is_linear(self) -> bool {
        matches!(self, Param::F0 | Param::Diffuse | Param::Specular)
    }
}

impl std::str::FromStr for Param {
    type Err = Error;
    fn from_str(s: &str) -> Result<Param> {
        Param::ALL
            .into_iter()
            .find(|p| p.name() == s.trim())
            .ok_or_else(|| {
                let names: Vec<&str> = Param::ALL.iter().map(|p| p.name()).collect();
                Error::Unsupported(format!(
                    "--free: unknown parameter `{s}`; expected some of: {}",
                    names.join(", ")
                ))
            })
    }
}

/// How a coordinate of the optimiser's vector maps to its parameter's value.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scale {
    /// The value itself.
    Linear,
    /// `ln(value)` (roughness: its effect is multiplicative).
    Log,
    /// `ln(1 + value)` (an exponent, which may be 0).
    Log1p,
}

impl Scale {
    fn to(self, x: f64) -> f64 {
        match self {
            Scale::Linear => x,
            Scale::Log => x.ln(),
            Scale::Log1p => x.ln_1p(),
        }
    }
    fn from(self, u: f64) -> f64 {
        match self {
            Scale::Linear => u,
            Scale::Log => u.exp(),
            Scale::Log1p => u.exp_m1(),
        }
    }
}

/// One scalar the optimiser moves: a parameter, its channel (`None`: one value for all),
/// its bounds (in the parameter's own units) and its scale.
#[derive(Debug, Clone, PartialEq)]
pub struct Coord {
    /// The parameter.
    pub param: Param,
    /// Its channel, or `None` for a value shared by R, G and B.
    pub channel: Option<usize>,
    /// Lower bound.
    pub lo: f64,
    /// Upper bound (may be infinite: an albedo).
    pub hi: f64,
    /// How the optimiser sees it.
    pub scale: Scale,
}

impl Coord {
    /// The optimiser's coordinate of `value`.
    pub fn to_u(&self, value: f64) -> f64 {
        self.scale.to(value)
    }
    /// The value of coordinate `u`, clamped to the bounds.
    pub fn value(&self, u: f64) -> f64 {
        self.scale.from(u).clamp(self.lo, self.hi)
    }
    /// `(lo, hi)` in the optimiser's coordinates.
    pub fn u_bounds(&self) -> (f64, f64) {
        (self.scale.to(self.lo), self.scale.to(self.hi))
    }
    /// `roughness`, `ior[1]`, …: how the report names it.
    pub fn label(&self) -> String {
        match self.channel {
            Some(c) => format!("{}[{c}]", self.param.name()),
            None => self.param.name().to_string(),
        }
    }
}

/// The linear coefficients per channel, in the material's units: `diffuse` = `d · c_diff`,
/// `specular` = `s · c_spec`, `f0` = Schlick's F0 (unused for other Fresnel terms).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Linear {
    /// `d · c_diff` (or `c_diff` for models without weights).
    pub diffuse: Rgb,
    /// `s · c_spec` (or `c_spec`).
    pub specular: Rgb,
    /// Schlick's F0.
    pub f0: Rgb,
}

/// The space a fit searches: the starting material, the free parameters, the nonlinear
/// coordinates and which linear coefficients are solved.
#[derive(Debug, Clone)]
pub struct Space {
    /// The starting material (fixed parameters come from it).
    pub start: Material,
    /// The free parameters as named.
    pub free: Vec<Param>,
    /// The optimiser's coordinates.
    pub coords: Vec<Coord>,
    /// Whether the free linear parameters are solved exactly (L2 losses) rather than
    /// being among [`Space::coords`].
    pub solve_linear: bool,
}

/// A user's bounds for one parameter (`--bound NAME=LO:HI`).
pub type UserBound = (Param, f64, f64);

impl Space {
    /// The space of `free` around `start`. Errors: no free parameter; a parameter the
    /// model does not have (F0 without Schlick, η without exact Fresnel, …); a model
    /// without continuous parameters to fit (measured data, anisotropic roughness);
    /// bounds outside the parameter's domain or excluding the start.
    pub fn new(
        start: &Material,
        free: &[Param],
        bounds: &[UserBound],
        solve_linear: bool,
    ) -> Result<Space> {
        let unsupported = |m: String| Error::Unsupported(format!("material `{}`: {m}", start.name));
        if free.is_empty() {
            return Err(unsupported(
                "no free parameter: name some with --free (e.g. --free roughness,diffuse,specular)"
                    .into(),
            ));
        }
        let mut coords = Vec::new();
        let mut seen = Vec::new();
        for &p in free {
            if seen.contains(&p) {
                continue;
            }
            seen.push(p);
            let have = has(start, p).map_err(unsupported)?;
            let (lo, hi) = match bounds.iter().find(|b| b.0 == p) {
                Some(&(_, lo, hi)) => (lo, hi),
                None => p.default_bounds(is_conductor(start)),
            };
            let (dlo, dhi) = p.default_bounds(is_conductor(start));
            if lo.is_nan() || hi.is_nan() || lo > hi || lo < dlo || hi > dhi {
                return Err(unsupported(format!(
                    "--bound {}={lo}:{hi}: give LO <= HI within the default bounds {dlo}:{dhi} (they may only narrow them)",
                    p.name()
                )));
            }
            let values = get(start, p);
            for (c, v) in values.iter().enumerate() {
                if !(lo..=hi).contains(v) {
                    return Err(unsupported(format!(
                        "the start's {}{} = {v} is outside the bounds [{lo}, {hi}]; start inside them (--materials/--material) or widen them (--bound {}=LO:HI)",
                        p.name(),
                        if values.len() > 1 { format!("[{c}]") } else { String::new() },
                        p.name()
                    )));
                }
            }
            if p.is_linear() && solve_linear {
                continue;
            }
            let scale = match p {
                Param::Roughness if lo > 0.0 => Scale::Log,
                Param::Exponent => Scale::Log1p,
                _ => Scale::Linear,
            };
            debug_assert!(have == values.len());
            for c in 0..values.len() {
                coords.push(Coord {
                    param: p,
                    channel: (values.len() == 3).then_some(c),
                    lo,
                    hi,
                    scale,
                });
            }
        }
        Ok(Space {
            start: start.clone(),
            free: seen,
            coords,
            solve_linear,
        })
    }

    /// Whether `p` is free.
    pub fn is_free(&self, p: Param) -> bool {
        self.free.contains(&p)
    }

    /// The start's coordinates.
    pub fn start_u(&self) -> Vec<f64> {
        self.coords
            .iter()
            .map(|c| c.to_u(get(&self.start, c.param)[c.channel.unwrap_or(0)]))
            .collect()
    }

    /// The start's linear coefficients.
    pub fn start_linear(&self) -> Linear {
        linear_of(&self.start)
    }

    /// The material at coordinates `u` with solved linear coefficients `solved` (see
    /// [`Space::linear_at`]).
    pub fn material(&self, u: &[f64], solved: &Linear) -> Material {
        let mut m = self.start.clone();
        for (c, &x) in self.coords.iter().zip(u) {
            set(&mut m, c.param, c.channel, c.value(x));
        }
        set_linear(&mut m, &self.linear_at(u, solved));
        m
    }

    /// The linear coefficients at `u`: a free one from `solved` when they are solved,
    /// else from its coordinates in `u`; one that is not free, the start's.
    pub fn linear_at(&self, u: &[f64], solved: &Linear) -> Linear {
        let start = linear_of(&self.start);
        let pick = |p: Param, fitted: Rgb, fixed: Rgb| if self.is_free(p) { fitted } else { fixed };
        let mut lin = Linear {
            diffuse: pick(Param::Diffuse, solved.diffuse, start.diffuse),
            specular: pick(Param::Specular, solved.specular, start.specular),
            f0: pick(Param::F0, solved.f0, start.f0),
        };
        for (c, &x) in self.coords.iter().zip(u) {
            let ch = c.channel.unwrap_or(0);
            match c.param {
                Param::Diffuse => lin.diffuse[ch] = c.value(x),
                Param::Specular => lin.specular[ch] = c.value(x),
                Param::F0 => lin.f0[ch] = c.value(x),
                _ => {}
            }
        }
        lin
    }

    /// The material one evaluation computes the specular basis with: the nonlinear
    /// parameters at `u`, no diffuse part, a unit specular albedo (same model and terms
    /// as the start at every `u`, so a kernel compiled for the first evaluation serves
    /// them all).
    pub fn basis_material(&self, u: &[f64]) -> Material {
        let mut m = self.material(u, &Linear::default());
        set_linear(
            &mut m,
            &Linear {
                diffuse: [0.0; 3],
                specular: [1.0; 3],
                f0: linear_of(&self.start).f0,
            },
        );
        if let Model::CookTorrance(ct) = &mut m.model {
            ct.diffuse_weight = 0.0;
            ct.specular_weight = 1.0;
        }
        m
    }

    /// Whether Schlick's F0 is free (its basis then comes from the terms D·G·K).
    pub fn f0_free(&self) -> bool {
        self.is_free(Param::F0)
    }

    /// Whether the model has a specular part at all (Lambert has none).
    pub fn has_specular(&self) -> bool {
        !matches!(self.start.model, Model::Lambert)
    }
}

fn is_conductor(m: &Material) -> bool {
    matches!(
        m.cook_torrance().map(|ct| ct.fresnel),
        Some(Fresnel::Conductor { .. })
    )
}

/// How many values `p` has in `m` (1 or 3), or why `m` does not have it.
fn has(m: &Material, p: Param) -> std::result::Result<usize, String> {
    let ct = m.cook_torrance();
    if let Model::Measured(_) = m.model {
        return Err(
            "a measured (merl) material has no parameters to fit; start from an analytic material"
                .into(),
        );
    }
    let model = m.model.toml_name();
    if m.is_anisotropic() {
        return Err("anisotropic roughness cannot be fitted to isotropic data; start from an isotropic material".into());
    }
    let no = |what: &str| {
        Err(format!(
            "`{}` is not a parameter of this {model} material ({what})",
            p.name()
        ))
    };
    match p {
        Param::Diffuse => Ok(3),
        Param::Specular if matches!(m.model, Model::Lambert) => no("lambert has no specular part"),
        Param::Specular => Ok(3),
        Param::Roughness => match (&m.model, ct.map(|c| c.distribution)) {
            (Model::Ward { .. }, _) => Ok(1),
            (
                _,
                Some(
                    Distribution::Beckmann(_)
                    | Distribution::Ggx(_)
                    | Distribution::Gaussian { .. },
                ),
            ) => Ok(1),
            _ => no("roughness belongs to ward and cook-torrance with beckmann, ggx or gaussian"),
        },
        Param::Exponent => match (&m.model, ct.map(|c| c.distribution)) {
            (Model::Phong { .. } | Model::BlinnPhong { .. } | Model::Rtr { .. }, _) => Ok(1),
            (_, Some(Distribution::Blinn { .. })) => Ok(1),
            _ => no("an exponent belongs to phong, blinn-phong, rtr and the blinn distribution"),
        },
        Param::F0 => match ct.map(|c| c.fresnel) {
            Some(Fresnel::Schlick { .. }) => Ok(3),
            _ => no("f0 needs fresnel = \"schlick\""),
        },
        Param::Ior => match ct.map(|c| c.fresnel) {
            Some(Fresnel::Conductor { .. }) => Ok(3),
            Some(Fresnel::Dielectric { ior }) if ior[0] == ior[1] && ior[1] == ior[2] => Ok(1),
            Some(Fresnel::Dielectric { .. }) => Err(
                "a dielectric's ior is fitted as one η for R, G and B; start from a grey ior"
                    .into(),
            ),
            _ => no("ior needs fresnel = \"dielectric\" or \"conductor\""),
        },
        Param::Extinction => match ct.map(|c| c.fresnel) {
            Some(Fresnel::Conductor { .. }) => Ok(3),
            _ => no("extinction needs fresnel = \"conductor\""),
        },
    }
}

/// The values of `p` in `m` (1 or 3; none when the model lacks it).
pub fn get(m: &Material, p: Param) -> Vec<f64> {
    let ct = m.cook_torrance();
    let lin = linear_of(m);
    match p {
        Param::Diffuse => lin.diffuse.to_vec(),
        Param::Specular => lin.specular.to_vec(),
        Param::F0 => lin.f0.to_vec(),
        Param::Roughness => match (&m.model, ct.map(|c| c.distribution)) {
            (Model::Ward { roughness }, _) => vec![roughness.xy().0],
            (_, Some(Distribution::Beckmann(r) | Distribution::Ggx(r))) => vec![r.xy().0],
            (_, Some(Distribution::Gaussian { m })) => vec![m],
            _ => vec![],
        },
        Param::Exponent => match (&m.model, ct.map(|c| c.distribution)) {
            (
                Model::Phong { exponent }
                | Model::BlinnPhong { exponent }
                | Model::Rtr { exponent },
                _,
            ) => vec![*exponent],
            (_, Some(Distribution::Blinn { exponent })) => vec![exponent],
            _ => vec![],
        },
        Param::Ior => match ct.map(|c| c.fresnel) {
            Some(Fresnel::Conductor { ior, .. }) => ior.to_vec(),
            Some(Fresnel::Dielectric { ior }) => vec![ior[0]],
            _ => vec![],
        },
        Param::Extinction => match ct.map(|c| c.fresnel) {
            Some(Fresnel::Conductor { extinction, .. }) => extinction.to_vec(),
            _ => vec![],
        },
    }
}

/// Sets a nonlinear parameter (`channel` `None`: every channel).
fn set(m: &mut Material, p: Param, channel: Option<usize>, x: f64) {
    let put = |rgb: &mut Rgb| match channel {
        Some(c) => rgb[c] = x,
        None => *rgb = [x; 3],
    };
    match (&mut m.model, p) {
        (Model::Ward { roughness }, Param::Roughness) => *roughness = Roughness::Isotropic(x),
        (
            Model::Phong { exponent } | Model::BlinnPhong { exponent } | Model::Rtr { exponent },
            Param::Exponent,
        ) => *exponent = x,
        (Model::CookTorrance(ct), _) => match (&mut ct.distribution, &mut ct.fresnel, p) {
            (Distribution::Beckmann(r) | Distribution::Ggx(r), _, Param::Roughness) => {
                *r = Roughness::Isotropic(x)
            }
            (Distribution::Gaussian { m }, _, Param::Roughness) => *m = x,
            (Distribution::Blinn { exponent }, _, Param::Exponent) => *exponent = x,
            (_, Fresnel::Conductor { ior, .. } | Fresnel::Dielectric { ior }, Param::Ior) => {
                put(ior)
            }
            (_, Fresnel::Conductor { extinction, .. }, Param::Extinction) => put(extinction),
            (_, Fresnel::Schlick { f0 }, Param::F0) => put(f0),
            _ => {}
        },
        _ => {}
    }
}

/// `m`'s linear coefficients.
fn linear_of(m: &Material) -> Linear {
    let (d, s, f0) = match m.cook_torrance() {
        Some(ct) => (
            ct.diffuse_weight,
            ct.specular_weight,
            match ct.fresnel {
                Fresnel::Schlick { f0 } => f0,
                _ => [0.0; 3],
            },
        ),
        None => (1.0, 1.0, [0.0; 3]),
    };
    Linear {
        diffuse: m.diffuse.map(|x| x * d),
        specular: m.specular.map(|x| x * s),
        f0,
    }
}

/// Writes linear coefficients into `m`: a Cook–Torrance weight of 0 becomes 1 when its
/// albedo is not 0 (else the colour keeps the ratio the start had).
fn set_linear(m: &mut Material, lin: &Linear) {
    let split = |albedo: Rgb, weight: &mut f64| -> Rgb {
        if *weight <= 0.0 {
            if albedo.iter().all(|&a| a == 0.0) {
                return [0.0; 3];
            }
            *weight = 1.0;
        }
        let w = *weight;
        albedo.map(|a| a / w)
    };
    match &mut m.model {
        Model::CookTorrance(ct) => {
            m.diffuse = split(lin.diffuse, &mut ct.diffuse_weight);
            m.specular = split(lin.specular, &mut ct.specular_weight);
            if let Fresnel::Schlick { f0 } = &mut ct.fresnel {
                *f0 = lin.f0.map(|x| x.clamp(0.0, 1.0));
            }
        }
        _ => {
            m.diffuse = lin.diffuse;
            m.specular = lin.specular;
        }
    }
}
