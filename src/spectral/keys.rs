//! A spectral `ior` in a materials file (FORMULAS.md §9): a shipped data set's name, inline
//! `[λ_nm, n, k]` (or `[λ_nm, n]`) rows, or `{ file = "x.yml" }` in refractiveindex.info's
//! format, and an `extinction` beside it. The parser (`material::parse`) asks these.

use super::{datasets, rii, Curve, IndexSpectrum, RgbReduction, SpectralIndex};
use crate::terms::FresnelKind;
use std::path::Path;
use toml::Value;

/// A material's spectral index from its `ior`, `extinction` and `rgb_reduction` values, for
/// the Fresnel term `fresnel` the file named; `None` when `ior` is absent or not a
/// spectrum (a number or RGB). Errors are `(key, message)`.
pub fn spectral_index(
    ior: Option<&Value>,
    extinction: Option<&Value>,
    reduction: Option<&Value>,
    fresnel: FresnelKind,
    base: &Path,
) -> Result<Option<SpectralIndex>, (&'static str, String)> {
    let Some(ior) = ior.filter(|v| is_spectrum(v)) else {
        return Ok(None);
    };
    let index = index_from(ior, extinction, base)?;
    let names = RgbReduction::ALL.map(RgbReduction::name).join(", ");
    let reduction = match reduction {
        None => RgbReduction::default(),
        Some(Value::String(n)) => RgbReduction::from_name(n).ok_or_else(|| {
            (
                "rgb_reduction",
                format!("unknown value `{n}`; expected one of: {names}"),
            )
        })?,
        Some(v) => {
            let found = v.type_str();
            return Err((
                "rgb_reduction",
                format!("expected a string (one of: {names}), found {found}"),
            ));
        }
    };
    Ok(Some(SpectralIndex {
        index,
        reduction,
        fresnel,
    }))
}

/// Whether a TOML `ior` value is a spectrum (a name, rows or a file), not a number or RGB.
fn is_spectrum(v: &Value) -> bool {
    match v {
        Value::String(_) | Value::Table(_) => true,
        Value::Array(items) => items.iter().any(|i| matches!(i, Value::Array(_))),
        _ => false,
    }
}

/// The spectrum of `ior` (and of `extinction`, when given: a number or `[λ_nm, k]` rows
/// replace the ior source's k). Errors are `(key, message)`.
fn index_from(
    ior: &Value,
    extinction: Option<&Value>,
    base: &Path,
) -> Result<IndexSpectrum, (&'static str, String)> {
    let mut index = match ior {
        Value::String(name) => datasets::dataset(name).ok_or_else(|| {
            (
                "ior",
                format!("unknown data set `{name}`; the shipped ones are: {} (or give [[λ_nm, n, k], …] rows, or {{ file = \"x.yml\" }})", datasets::names()),
            )
        })?,
        Value::Table(t) => {
            let file = match (t.get("file"), t.len()) {
                (Some(Value::String(f)), 1) => f,
                _ => return Err(("ior", "a table here is `{ file = \"x.yml\" }` (a refractiveindex.info file)".into())),
            };
            let path = base.join(file);
            let text = std::fs::read_to_string(&path)
                .map_err(|e| ("ior", format!("cannot read `{}`: {e}", path.display())))?;
            rii::parse(&text, &path.display().to_string()).map_err(|m| ("ior", m))?
        }
        Value::Array(items) => {
            let rows = rows(items, &[2, 3]).map_err(|m| ("ior", m))?;
            let col = |c: usize| Curve::table(rows.iter().map(|r| (r[0], r[c])).collect());
            IndexSpectrum {
                source: "inline rows".into(),
                n: col(1).map_err(|m| ("ior", m))?,
                k: if rows[0].len() == 3 {
                    col(2).map_err(|m| ("ior", m))?
                } else {
                    Curve::Constant(0.0)
                },
            }
        }
        _ => return Err(("ior", "not a spectrum".into())),
    };
    match extinction {
        None => {}
        Some(Value::Float(_) | Value::Integer(_)) => {
            let k = extinction
                .and_then(Value::as_float)
                .or(extinction.and_then(Value::as_integer).map(|i| i as f64));
            match k {
                Some(k) if k.is_finite() && k >= 0.0 => index.k = Curve::Constant(k),
                _ => return Err(("extinction", "must be a finite number ≥ 0".into())),
            }
        }
        Some(Value::Array(items)) if items.iter().all(|i| matches!(i, Value::Array(_))) => {
            let rows = rows(items, &[2]).map_err(|m| ("extinction", m))?;
            index.k = Curve::table(rows.iter().map(|r| (r[0], r[1])).collect())
                .map_err(|m| ("extinction", m))?;
        }
        Some(_) => {
            return Err((
                "extinction",
                "with a spectral `ior`, `extinction` is a number or [[λ_nm, k], …] rows (not RGB)"
                    .into(),
            ))
        }
    }
    check_values(&index)?;
    Ok(index)
}

/// Rows of numbers, each of one of the lengths `widths` (all rows the same).
fn rows(items: &[Value], widths: &[usize]) -> Result<Vec<Vec<f64>>, String> {
    let out: Vec<Vec<f64>> = items
        .iter()
        .enumerate()
        .map(|(i, r)| match r {
            Value::Array(xs) => xs
                .iter()
                .map(|x| match x {
                    Value::Float(f) => Ok(*f),
                    Value::Integer(v) => Ok(*v as f64),
                    _ => Err(format!("row {}: not a number", i + 1)),
                })
                .collect::<Result<Vec<f64>, String>>(),
            _ => Err(format!("row {}: expected [λ_nm, value, …]", i + 1)),
        })
        .collect::<Result<_, _>>()?;
    let w = out.first().map_or(0, Vec::len);
    if !widths.contains(&w) || out.iter().any(|r| r.len() != w) {
        let want: Vec<String> = widths.iter().map(usize::to_string).collect();
        return Err(format!(
            "rows of {} numbers each ([λ_nm, n, k] or [λ_nm, n])",
            want.join(" or ")
        ));
    }
    Ok(out)
}

/// n > 0 and k ≥ 0 at every row of a table (the formulas are checked where evaluated).
fn check_values(index: &IndexSpectrum) -> Result<(), (&'static str, String)> {
    for (key, curve, min) in [("ior", &index.n, 1e-6), ("extinction", &index.k, 0.0)] {
        if let Curve::Table(rows) = curve {
            if let Some(r) = rows.iter().find(|r| !(r.1 >= min && r.1 <= 1e18)) {
                return Err((
                    key,
                    format!("{} at {} nm is out of range [{min}, 1e18]", r.1, r.0),
                ));
            }
        }
    }
    Ok(())
}
