//! TOML materials: `[[material]]` tables, presets plus overrides, and validation with
//! errors that name the file, line, material and key.

use super::model::{CookTorrance, Material, Measured, Model};
use super::preset_toml;
use super::ranges::*;
use crate::error::MaterialError;
use crate::terms::f::schlick::f0_from_ior;
use crate::terms::{
    Convention, Distribution, DistributionKind, Fresnel, FresnelKind, Geometry, Rgb, Roughness,
};
use std::collections::BTreeMap;
use std::path::Path;
use toml::{Spanned, Value};

/// Every key a `[[material]]` table may hold.
const KEYS: &[&str] = &[
    "name",
    "preset",
    "model",
    "convention",
    "distribution",
    "roughness",
    "exponent",
    "geometry",
    "fresnel",
    "ior",
    "extinction",
    "f0",
    "diffuse",
    "specular",
    "specular_weight",
    "diffuse_weight",
    "file",
    "lookup",
    "precision",
    "sigma0",
    "tau",
    "wavelengths",
    "rgb_reduction",
];

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct Document {
    #[serde(default)]
    material: Vec<Spanned<BTreeMap<String, Spanned<Value>>>>,
}

/// The most materials one file may hold: the tuples' material column is a float32, which
/// represents every integer only up to 2^24.
pub const MAX_MATERIALS: usize = 1 << 24;

/// Reads and validates a materials file.
pub fn load_materials(path: &Path) -> crate::Result<Vec<Material>> {
    let text = std::fs::read_to_string(path).map_err(|source| crate::Error::Io {
        path: path.to_owned(),
        source,
    })?;
    let base = path.parent().unwrap_or(Path::new("."));
    Ok(parse_materials_in(
        &text,
        &path.display().to_string(),
        base,
    )?)
}

/// Parses and validates TOML text holding `[[material]]` tables. `source_name` is used in
/// error messages (normally the file name).
pub fn parse_materials(text: &str, source_name: &str) -> Result<Vec<Material>, MaterialError> {
    parse_materials_in(text, source_name, Path::new("."))
}

/// [`parse_materials`] with relative `file` paths (measured materials) resolved against
/// `base` (the materials file's directory).
pub fn parse_materials_in(
    text: &str,
    source_name: &str,
    base: &Path,
) -> Result<Vec<Material>, MaterialError> {
    let lines = LineIndex::new(text);
    let doc: Document = toml::from_str(text).map_err(|e| MaterialError {
        source_name: source_name.to_string(),
        line: e.span().map(|s| lines.line(s.start)),
        material: None,
        key: None,
        message: e.message().trim().to_string(),
    })?;
    if doc.material.is_empty() {
        return Err(MaterialError {
            source_name: source_name.to_string(),
            line: None,
            material: None,
            key: None,
            message: "no [[material]] tables found; see `vkbrdf materials --help` for the format"
                .into(),
        });
    }
    if doc.material.len() > MAX_MATERIALS {
        return Err(MaterialError {
            source_name: source_name.to_string(),
            line: None,
            material: None,
            key: None,
            message: format!(
                "{} materials; at most {MAX_MATERIALS} (2^24): the tuples' material column is a float32, which holds every integer only up to 2^24",
                doc.material.len()
            ),
        });
    }
    let mut out: Vec<Material> = Vec::with_capacity(doc.material.len());
    // Names seen so far: a hash set keeps the duplicate check linear (comparing each name
    // with every earlier one took over 20 minutes for 938,213 materials).
    let mut names: std::collections::HashSet<String> =
        std::collections::HashSet::with_capacity(doc.material.len());
    for table in &doc.material {
        let ctx = Ctx {
            source_name,
            base,
            lines: &lines,
            table_line: lines.line(table.span().start),
        };
        let m = ctx.material(table.get_ref())?;
        if !names.insert(m.name.clone()) {
            return Err(ctx.err(
                Some(&m.name),
                Some("name"),
                None,
                "duplicate material name".into(),
            ));
        }
        out.push(m);
    }
    Ok(out)
}

/// Parses one preset's definition (used by [`super::presets`]).
pub(super) fn parse_preset(name: &str, body: &str) -> Result<Material, MaterialError> {
    let text = format!("[[material]]\nname = \"{name}\"\n{body}");
    let mut v = parse_materials(&text, &format!("preset `{name}`"))?;
    Ok(v.remove(0))
}

struct LineIndex(Vec<usize>);
impl LineIndex {
    fn new(text: &str) -> Self {
        LineIndex(text.match_indices('\n').map(|(i, _)| i).collect())
    }
    fn line(&self, offset: usize) -> usize {
        self.0.partition_point(|&nl| nl < offset) + 1
    }
}

struct Ctx<'a> {
    source_name: &'a str,
    base: &'a Path,
    lines: &'a LineIndex,
    table_line: usize,
}

/// A key's value and where it came from (`None` line: from a preset).
struct Entry<'v> {
    value: &'v Value,
    line: Option<usize>,
}

struct Fields<'v, 'c> {
    ctx: &'c Ctx<'c>,
    name: String,
    map: BTreeMap<String, Entry<'v>>,
    used: Vec<&'static str>,
    /// A spectral `ior`, once read (FORMULAS.md §9).
    spectral: Option<std::sync::Arc<crate::spectral::SpectralIndex>>,
}

impl Ctx<'_> {
    fn err(
        &self,
        material: Option<&str>,
        key: Option<&str>,
        line: Option<usize>,
        message: String,
    ) -> MaterialError {
        MaterialError {
            source_name: self.source_name.to_string(),
            line: line.or(Some(self.table_line)),
            material: material.map(str::to_string),
            key: key.map(str::to_string),
            message,
        }
    }

    fn material(
        &self,
        table: &BTreeMap<String, Spanned<Value>>,
    ) -> Result<Material, MaterialError> {
        let name = match table.get("name") {
            Some(v) => match v.get_ref() {
                // A control character (a newline, NUL) would break every listing and
                // report that prints the name on one line.
                Value::String(s) if s.chars().any(char::is_control) => {
                    return Err(self.err(
                        None,
                        Some("name"),
                        Some(self.lines.line(v.span().start)),
                        format!("{s:?} holds a control character (a newline, tab or NUL); names are printed on one line"),
                    ))
                }
                Value::String(s) if !s.trim().is_empty() => s.clone(),
                _ => {
                    return Err(self.err(
                        None,
                        Some("name"),
                        Some(self.lines.line(v.span().start)),
                        "must be a non-empty string".into(),
                    ))
                }
            },
            None => {
                return Err(self.err(
                    None,
                    Some("name"),
                    None,
                    "every [[material]] needs a `name`".into(),
                ))
            }
        };
        for (k, v) in table {
            if !KEYS.contains(&k.as_str()) {
                return Err(self.err(
                    Some(&name),
                    Some(k),
                    Some(self.lines.line(v.span().start)),
                    format!("unknown key; the keys are: {}", KEYS.join(", ")),
                ));
            }
        }
        // Preset first, then the table's own keys override it.
        let mut map: BTreeMap<String, Entry> = BTreeMap::new();
        let preset_storage;
        if let Some(p) = table.get("preset") {
            let line = Some(self.lines.line(p.span().start));
            let pname = match p.get_ref() {
                Value::String(s) => s.as_str(),
                _ => {
                    return Err(self.err(
                        Some(&name),
                        Some("preset"),
                        line,
                        "must be a string".into(),
                    ))
                }
            };
            let body = preset_toml::body(pname).ok_or_else(|| {
                self.err(
                    Some(&name),
                    Some("preset"),
                    line,
                    format!(
                        "unknown preset `{pname}`; the presets are: {}",
                        preset_toml::NAMES.join(", ")
                    ),
                )
            })?;
            preset_storage = body
                .parse::<toml::Table>()
                .expect("preset bodies are valid TOML (tested)");
            // A table that changes the preset's model would silently drop everything the
            // preset set (its Fresnel, roughness, …): refuse it.
            let preset_model = preset_storage.get("model").and_then(|v| v.as_str());
            if let (Some(own), Some(pm)) = (table.get("model"), preset_model) {
                if own.get_ref().as_str().is_some_and(|m| m != pm) {
                    return Err(self.err(
                        Some(&name),
                        Some("model"),
                        Some(self.lines.line(own.span().start)),
                        format!(
                            "preset `{pname}` is a `{pm}` material; a different `model` would drop what the preset sets — remove `preset` or `model`"
                        ),
                    ));
                }
            }
            for (k, v) in &preset_storage {
                map.insert(
                    k.clone(),
                    Entry {
                        value: v,
                        line: None,
                    },
                );
            }
        }
        for (k, v) in table {
            if k != "name" && k != "preset" {
                map.insert(
                    k.clone(),
                    Entry {
                        value: v.get_ref(),
                        line: Some(self.lines.line(v.span().start)),
                    },
                );
            }
        }
        let mut f = Fields {
            ctx: self,
            name,
            map,
            used: vec![],
            spectral: None,
        };
        let m = f.build()?;
        f.reject_unused()?;
        Ok(m)
    }
}

impl Fields<'_, '_> {
    fn err(&self, key: &str, message: String) -> MaterialError {
        let line = self.map.get(key).and_then(|e| e.line);
        self.ctx.err(Some(&self.name), Some(key), line, message)
    }

    fn has(&self, key: &str) -> bool {
        self.map.contains_key(key)
    }

    fn take(&mut self, key: &'static str) -> Option<Value> {
        self.used.push(key);
        self.map.get(key).map(|e| e.value.clone())
    }

    fn string(
        &mut self,
        key: &'static str,
        choices: &[&str],
    ) -> Result<Option<String>, MaterialError> {
        match self.take(key) {
            None => Ok(None),
            Some(Value::String(s)) if choices.contains(&s.as_str()) => Ok(Some(s)),
            Some(Value::String(s)) => Err(self.err(
                key,
                format!(
                    "unknown value `{s}`; expected one of: {}",
                    choices.join(", ")
                ),
            )),
            Some(v) => Err(self.err(
                key,
                format!(
                    "expected a string (one of: {}), found {}",
                    choices.join(", "),
                    v.type_str()
                ),
            )),
        }
    }

    fn required_string(
        &mut self,
        key: &'static str,
        choices: &[&str],
        why: &str,
    ) -> Result<String, MaterialError> {
        self.string(key, choices)?.ok_or_else(|| {
            self.err(
                key,
                format!("missing; {why} (one of: {})", choices.join(", ")),
            )
        })
    }

    fn number_of(&self, key: &str, v: &Value) -> Result<f64, MaterialError> {
        match v {
            Value::Float(x) => Ok(*x),
            Value::Integer(i) => Ok(*i as f64),
            other => Err(self.err(
                key,
                format!("expected a number, found {}", other.type_str()),
            )),
        }
    }

    /// A scalar; `check` returns an error message when the value is out of range.
    fn scalar(
        &mut self,
        key: &'static str,
        check: fn(f64) -> Option<&'static str>,
    ) -> Result<Option<f64>, MaterialError> {
        let Some(v) = self.take(key) else {
            return Ok(None);
        };
        if let Value::Array(_) = v {
            return Err(self.err(key, "expected a number, found an array".into()));
        }
        let x = self.number_of(key, &v)?;
        match check(x) {
            Some(msg) => Err(self.err(key, format!("{msg} (got {})", shown(x)))),
            None => Ok(Some(x)),
        }
    }

    /// A number or an array of `len` numbers (a scalar is broadcast when `broadcast`).
    fn vector(
        &mut self,
        key: &'static str,
        len: usize,
        check: fn(f64) -> Option<&'static str>,
    ) -> Result<Option<Vec<f64>>, MaterialError> {
        let Some(v) = self.take(key) else {
            return Ok(None);
        };
        let xs = match &v {
            Value::Array(items) => {
                if items.len() != len {
                    return Err(self.err(
                        key,
                        format!(
                            "expected a number or an array of {len} numbers, found an array of {}",
                            items.len()
                        ),
                    ));
                }
                items
                    .iter()
                    .map(|i| self.number_of(key, i))
                    .collect::<Result<Vec<_>, _>>()?
            }
            other => vec![self.number_of(key, other)?],
        };
        for &x in &xs {
            if let Some(msg) = check(x) {
                return Err(self.err(key, format!("{msg} (got {})", shown(x))));
            }
        }
        Ok(Some(xs))
    }

    fn rgb(
        &mut self,
        key: &'static str,
        check: fn(f64) -> Option<&'static str>,
    ) -> Result<Option<Rgb>, MaterialError> {
        Ok(self.vector(key, 3, check)?.map(|v| {
            if v.len() == 1 {
                [v[0]; 3]
            } else {
                [v[0], v[1], v[2]]
            }
        }))
    }

    fn roughness(&mut self, required_for: &str) -> Result<Roughness, MaterialError> {
        let v = self.vector("roughness", 2, roughness_range)?.ok_or_else(|| {
            self.err(
                "roughness",
                format!("missing; {required_for} needs `roughness` (a number in [1e-7, 1e4], or [mx, my])"),
            )
        })?;
        Ok(if v.len() == 1 {
            Roughness::Isotropic(v[0])
        } else {
            Roughness::Anisotropic(v[0], v[1])
        })
    }

    fn exponent(&mut self, required_for: &str) -> Result<f64, MaterialError> {
        self.scalar("exponent", exponent_range)?.ok_or_else(|| {
            self.err(
                "exponent",
                format!("missing; {required_for} needs `exponent` (a number in [0, 1e18])"),
            )
        })
    }

    fn build(&mut self) -> Result<Material, MaterialError> {
        let model = self.required_string(
            "model",
            &[
                "lambert",
                "phong",
                "blinn-phong",
                "rtr",
                "ward",
                "cook-torrance",
                "merl",
                "htsg",
            ],
            "every material states its model",
        )?;
        if model == "merl" {
            // Measured data carries its own colour: diffuse/specular do not apply.
            if self.string("precision", &["exact", "fast"])?.as_deref() == Some("fast") {
                return Err(self.err(
                    "precision",
                    "a measured material has no fast variant (it is a table lookup)".into(),
                ));
            }
            return Ok(Material {
                name: self.name.clone(),
                model: Model::Measured(self.measured()?),
                diffuse: [0.0; 3],
                specular: [1.0; 3],
                precision: super::precision::Precision::Exact,
                spectral: None,
            });
        }
        let diffuse = self.rgb("diffuse", colour_range)?.unwrap_or([0.0; 3]);
        if model == crate::terms::htsg::NAME {
            // "exact" is its only variant: a "fast" fails here, naming the choice.
            self.string("precision", &["exact"])?;
            return Ok(Material {
                name: self.name.clone(),
                model: Model::Htsg(self.htsg()?),
                diffuse,
                specular: [1.0; 3],
                precision: super::precision::Precision::Exact,
                spectral: self.spectral.take(),
            });
        }
        let specular = if model == "lambert" {
            [1.0; 3]
        } else {
            self.rgb("specular", colour_range)?.unwrap_or([1.0; 3])
        };
        let model = match model.as_str() {
            "lambert" => Model::Lambert,
            "phong" => Model::Phong {
                exponent: self.exponent("model `phong`")?,
            },
            "blinn-phong" => Model::BlinnPhong {
                exponent: self.exponent("model `blinn-phong`")?,
            },
            "rtr" => Model::Rtr {
                exponent: self.exponent("model `rtr`")?,
            },
            "ward" => Model::Ward {
                roughness: self.roughness("model `ward`")?,
            },
            _ => Model::CookTorrance(self.cook_torrance()?),
        };
        let precision = match self.string("precision", &["exact", "fast"])?.as_deref() {
            Some("fast") => super::precision::Precision::Fast,
            _ => super::precision::Precision::Exact,
        };
        let material = Material {
            name: self.name.clone(),
            model,
            diffuse,
            specular,
            precision: super::precision::Precision::Exact,
            spectral: self.spectral.take(),
        };
        Ok(super::precision::apply(&material, precision))
    }

    /// The parameters of an `htsg` material (FORMULAS.md §8): `sigma0` and `tau` in µm,
    /// `ior` and `extinction` per channel, `wavelengths` in nm.
    fn htsg(&mut self) -> Result<crate::terms::htsg::Htsg, MaterialError> {
        use crate::terms::htsg;
        let why =
            "model `htsg` needs `sigma0` and `tau` (µm) and `ior` (`extinction` defaults to 0)";
        let sigma0 = self
            .scalar("sigma0", htsg::sigma0_range)?
            .ok_or_else(|| self.err("sigma0", format!("missing; {why}")))?;
        let tau = self
            .scalar("tau", htsg::tau_range)?
            .ok_or_else(|| self.err("tau", format!("missing; {why}")))?;
        if let Some((key, message)) = htsg::legality(sigma0, tau) {
            return Err(self.err(key, message));
        }
        let nm = self
            .rgb("wavelengths", htsg::wavelength_range)?
            .unwrap_or(htsg::DEFAULT_WAVELENGTHS_NM);
        // A spectral index is read at the material's own wavelengths for its RGB form.
        let (ior, extinction) = if let Some(s) = self.spectral_ior(FresnelKind::Conductor)? {
            let at = |l: f64| s.index.at(l).map_err(|m| self.err("ior", m));
            let p = [at(nm[0])?, at(nm[1])?, at(nm[2])?];
            (p.map(|x| x.0.max(1e-6)), p.map(|x| x.1))
        } else {
            let ior = self
                .rgb("ior", ior_range)?
                .ok_or_else(|| self.err("ior", format!("missing; {why} (n per channel)")))?;
            (
                ior,
                self.rgb("extinction", extinction_range)?
                    .unwrap_or([0.0; 3]),
            )
        };
        Ok(htsg::Htsg {
            sigma0,
            tau,
            ior,
            extinction,
            wavelengths: nm.map(|x| x / 1000.0),
        })
    }

    /// `file = "x.binary"`: a MERL file, relative to the materials file's directory.
    fn measured(&mut self) -> Result<Measured, MaterialError> {
        let file = match self.take("file") {
            Some(Value::String(s)) => s,
            Some(v) => {
                return Err(self.err(
                    "file",
                    format!(
                        "expected a string (a MERL .binary path), found {}",
                        v.type_str()
                    ),
                ))
            }
            None => return Err(self.err(
                "file",
                "missing; model `merl` needs `file` (a MERL .binary path, relative to this file)"
                    .into(),
            )),
        };
        let path = self.ctx.base.join(&file);
        // The whole chain: an I/O error's own text names only the path, its source says
        // why (no such file, permission denied).
        let data = super::merl::read(&path).map_err(|e| {
            let mut why = e.to_string();
            let mut source = std::error::Error::source(&e);
            while let Some(s) = source {
                why += &format!(": {s}");
                source = s.source();
            }
            self.err("file", format!("cannot use `{file}`: {why}"))
        })?;
        let lookup = match self.string("lookup", &["nearest", "linear"])?.as_deref() {
            Some("linear") => super::merl::Lookup::Linear,
            _ => super::merl::Lookup::Nearest,
        };
        Ok(Measured {
            path,
            data: std::sync::Arc::new(data),
            lookup,
        })
    }

    fn cook_torrance(&mut self) -> Result<CookTorrance, MaterialError> {
        let names = Convention::ALL.map(Convention::toml_name);
        let convention = match self.string("convention", &names)? {
            Some(c) => Convention::from_toml_name(&c).expect("one of the names offered"),
            None => Convention::Modern,
        };
        let why = "a cook-torrance material states its distribution, geometry and fresnel";
        let names = DistributionKind::ALL.map(DistributionKind::toml_name);
        let dist = self.required_string("distribution", &names, why)?;
        let kind = DistributionKind::from_toml_name(&dist).expect("one of the names offered");
        let distribution = if kind.takes_exponent() {
            Distribution::Blinn {
                exponent: self.exponent("distribution `blinn`")?,
            }
        } else {
            let r = self.roughness(&format!("distribution `{dist}`"))?;
            // The distribution's own rules first (FORMULAS.md §2), whatever the geometry.
            self.legal(convention, kind, r.is_anisotropic(), Geometry::None)?;
            if let (Some(max), Roughness::Isotropic(m)) = (kind.max_roughness(), r) {
                if m > max {
                    return Err(self.err("roughness", format!("{} is out of range: distribution `{dist}` needs 0 < m ≤ {max} (m is Estevez & Kulla's α = r², not an rms slope)", shown(m))));
                }
            }
            kind.with_roughness(r)
                .expect("legality refused the roughness this kind does not take")
        };
        let names = Geometry::ALL.map(Geometry::toml_name);
        let geometry = Geometry::from_toml_name(&self.required_string("geometry", &names, why)?)
            .expect("one of the names offered");
        self.legal(
            convention,
            kind,
            distribution_is_anisotropic(&distribution),
            geometry,
        )?;
        let fresnel = self.fresnel()?;
        let specular_weight = self.scalar("specular_weight", colour_range)?.unwrap_or(1.0);
        let diffuse_weight = self.scalar("diffuse_weight", colour_range)?.unwrap_or(0.0);
        Ok(CookTorrance {
            convention,
            distribution,
            geometry,
            fresnel,
            specular_weight,
            diffuse_weight,
        })
    }

    /// [`super::legality`], its message on the key it names.
    fn legal(
        &self,
        convention: Convention,
        kind: DistributionKind,
        anisotropic: bool,
        geometry: Geometry,
    ) -> Result<(), MaterialError> {
        crate::terms::legality(convention, kind, anisotropic, geometry)
            .map_err(|e| self.err(e.key, e.message))
    }

    fn fresnel(&mut self) -> Result<Fresnel, MaterialError> {
        let names = FresnelKind::ALL.map(FresnelKind::toml_name);
        let why = "a cook-torrance material states its distribution, geometry and fresnel";
        let name = self.required_string("fresnel", &names, why)?;
        let kind = FresnelKind::from_toml_name(&name).expect("one of the names offered");
        if kind == FresnelKind::Dielectric && self.has("extinction") {
            self.used.push("extinction");
            return Err(self.err(
                "extinction",
                "`dielectric` has a real IOR; for a complex IOR use fresnel = \"conductor\"".into(),
            ));
        }
        if kind != FresnelKind::None && !(kind == FresnelKind::Schlick && self.has("f0")) {
            if let Some(s) = self.spectral_ior(kind)? {
                return crate::spectral::colour::rgb_fresnel(kind, &s.index, s.reduction)
                    .map_err(|m| self.err("ior", m));
            }
        }
        Ok(match kind {
            FresnelKind::None => Fresnel::None,
            FresnelKind::Dielectric => {
                let ior = self.rgb("ior", ior_range)?.ok_or_else(|| {
                    self.err(
                        "ior",
                        "missing; fresnel `dielectric` needs `ior` (a number in [1e-6, 1e18] or RGB)".into(),
                    )
                })?;
                Fresnel::Dielectric { ior }
            }
            FresnelKind::Conductor => {
                let ior = self.rgb("ior", ior_range)?.ok_or_else(|| {
                    self.err(
                        "ior",
                        "missing; fresnel `conductor` needs `ior` and `extinction`".into(),
                    )
                })?;
                let extinction = self.rgb("extinction", extinction_range)?.ok_or_else(|| {
                    self.err(
                        "extinction",
                        "missing; fresnel `conductor` needs `extinction` (RGB k in [0, 1e18])"
                            .into(),
                    )
                })?;
                Fresnel::Conductor { ior, extinction }
            }
            FresnelKind::Schlick => {
                let f0 = self.rgb("f0", unit_interval)?;
                let ior = self.rgb("ior", ior_range)?;
                let ext = self.rgb("extinction", extinction_range)?;
                match (f0, ior) {
                    (Some(_), Some(_)) => return Err(self.err("f0", "give either `f0` or `ior` (and `extinction`) for schlick, not both".into())),
                    (Some(f0), None) if ext.is_some() => { let _ = f0; return Err(self.err("extinction", "`extinction` needs `ior`; with `f0` given, drop it".into())) }
                    (Some(f0), None) => Fresnel::Schlick { f0 },
                    (None, Some(ior)) => Fresnel::Schlick { f0: f0_from_ior(ior, ext.unwrap_or([0.0; 3])) },
                    (None, None) => return Err(self.err("f0", "missing; fresnel `schlick` needs `f0` (RGB in [0, 1]) or `ior` (and optionally `extinction`)".into())),
                }
            }
        })
    }

    /// A spectral `ior` (FORMULAS.md §9) with its `extinction` and `rgb_reduction`, kept for
    /// the material (and returned); `None` when `ior` is absent or a number or RGB.
    fn spectral_ior(
        &mut self,
        fresnel: FresnelKind,
    ) -> Result<Option<std::sync::Arc<crate::spectral::SpectralIndex>>, MaterialError> {
        let value = |key: &str| self.map.get(key);
        let found = crate::spectral::keys::spectral_index(
            value("ior").map(|e| e.value),
            // A preset's RGB extinction gives way to the table's spectral ior (its data has k).
            value("extinction")
                .filter(|e| e.line.is_some())
                .map(|e| e.value),
            value("rgb_reduction").map(|e| e.value),
            fresnel,
            self.ctx.base,
        )
        .map_err(|(key, m)| self.err(key, m))?;
        let Some(spectral) = found else {
            return Ok(None);
        };
        self.used.extend(["ior", "extinction", "rgb_reduction"]);
        self.spectral = Some(std::sync::Arc::new(spectral));
        Ok(self.spectral.clone())
    }

    /// Keys the table set (not the preset) that the chosen model never reads are errors:
    /// they are almost always a typo or a misunderstanding.
    fn reject_unused(&self) -> Result<(), MaterialError> {
        for (k, e) in &self.map {
            if e.line.is_some() && !self.used.contains(&k.as_str()) {
                return Err(self.err(k, "does not apply to this material (its model, distribution or fresnel never reads it)".into()));
            }
        }
        Ok(())
    }
}

fn distribution_is_anisotropic(d: &Distribution) -> bool {
    matches!(d, Distribution::Beckmann(r) | Distribution::Ggx(r) if r.is_anisotropic())
}
