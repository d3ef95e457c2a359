//! Files in refractiveindex.info's YAML format (its database is CC0): `DATA` entries of type
//! `tabulated nk`, `tabulated n`, `tabulated k`, `formula 1` and `formula 2`, wavelengths in
//! µm (converted to nm here). A missing k is 0. The YAML itself is read by `yaml-rust2`.

use super::index::{Curve, IndexSpectrum};
use yaml_rust2::{Yaml, YamlLoader};

/// Parses a refractiveindex.info file's text; `source` names it in errors and reports.
pub fn parse(text: &str, source: &str) -> Result<IndexSpectrum, String> {
    let docs = YamlLoader::load_from_str(text).map_err(|e| format!("{source}: not YAML: {e}"))?;
    let doc = docs
        .first()
        .ok_or_else(|| format!("{source}: empty file"))?;
    let Yaml::Array(entries) = &doc["DATA"] else {
        return Err(format!(
            "{source}: no `DATA:` list (a refractiveindex.info file has `DATA: - type: tabulated nk ...`)"
        ));
    };
    let (mut n, mut k) = (None::<Curve>, None::<Curve>);
    for (i, e) in entries.iter().enumerate() {
        let at = format!("{source}: DATA entry {}", i + 1);
        let kind = scalar(&e["type"]).ok_or_else(|| format!("{at}: no `type`"))?;
        let set = |slot: &mut Option<Curve>, c: Curve, what: &str| {
            if slot.is_some() {
                return Err(format!("{at}: a second {what} (the file already gave one)"));
            }
            *slot = Some(c);
            Ok(())
        };
        match kind.as_str() {
            "tabulated nk" | "tabulated n" | "tabulated k" => {
                let want = if kind == "tabulated nk" { 3 } else { 2 };
                let rows = table(&e["data"], want).map_err(|m| format!("{at} ({kind}): {m}"))?;
                let column = |c: usize| {
                    Curve::table(rows.iter().map(|r| (r[0] * 1000.0, r[c])).collect())
                        .map_err(|m| format!("{at} ({kind}): {m}"))
                };
                match kind.as_str() {
                    "tabulated nk" => {
                        set(&mut n, column(1)?, "n")?;
                        set(&mut k, column(2)?, "k")?;
                    }
                    "tabulated n" => set(&mut n, column(1)?, "n")?,
                    _ => set(&mut k, column(1)?, "k")?,
                }
            }
            "formula 1" | "formula 2" => {
                let coefficients = numbers(&e["coefficients"])
                    .ok_or_else(|| format!("{at} ({kind}): no numeric `coefficients`"))?;
                let range = numbers(&e["wavelength_range"])
                    .filter(|r| r.len() == 2 && r[0] > 0.0 && r[0] < r[1])
                    .ok_or_else(|| format!("{at} ({kind}): `wavelength_range` must be two increasing numbers (µm)"))?;
                let range_nm = (range[0] * 1000.0, range[1] * 1000.0);
                let c = if kind == "formula 1" {
                    Curve::Sellmeier1 { coefficients, range_nm }
                } else {
                    Curve::Sellmeier2 { coefficients, range_nm }
                };
                set(&mut n, c, "n")?;
            }
            other => {
                return Err(format!(
                    "{at}: type `{other}` is not supported (vkbrdf reads tabulated nk, tabulated n, tabulated k, formula 1 and formula 2)"
                ))
            }
        }
    }
    Ok(IndexSpectrum {
        source: source.to_owned(),
        n: n.ok_or_else(|| {
            format!("{source}: no n (a `tabulated nk`, `tabulated n` or formula entry)")
        })?,
        k: k.unwrap_or(Curve::Constant(0.0)),
    })
}

/// A YAML scalar as text.
fn scalar(y: &Yaml) -> Option<String> {
    match y {
        Yaml::String(s) | Yaml::Real(s) => Some(s.trim().to_owned()),
        Yaml::Integer(i) => Some(i.to_string()),
        _ => None,
    }
}

/// Whitespace-separated numbers.
fn numbers(y: &Yaml) -> Option<Vec<f64>> {
    scalar(y)?
        .split_whitespace()
        .map(|x| x.parse::<f64>().ok())
        .collect()
}

/// The rows of a `data: |` block, `columns` numbers each.
fn table(y: &Yaml, columns: usize) -> Result<Vec<Vec<f64>>, String> {
    let text = scalar(y).ok_or("no `data` block")?;
    text.lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(i, l)| {
            let row: Vec<f64> = l
                .split_whitespace()
                .map(|x| x.parse::<f64>())
                .collect::<Result<_, _>>()
                .map_err(|_| format!("data line {}: `{}` is not numbers", i + 1, l.trim()))?;
            if row.len() != columns {
                return Err(format!(
                    "data line {}: {} numbers, expected {columns}",
                    i + 1,
                    row.len()
                ));
            }
            Ok(row)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_supported_form_reads() {
        let nk = "DATA:\n  - type: tabulated nk\n    data: |\n        0.4 1.5 0.1\n        0.5 1.4 0.2\n";
        let s = parse(nk, "t").unwrap();
        assert_eq!(s.at(450.0).unwrap(), (1.45, 0.15000000000000002));
        let split = "DATA:\n  - type: tabulated n\n    data: |\n        0.4 1.5\n        0.6 1.3\n  - type: tabulated k\n    data: |\n        0.3 0.0\n        0.7 0.4\n";
        let s = parse(split, "t").unwrap();
        assert_eq!(s.range(), (400.0, 600.0));
        assert!((s.at(500.0).unwrap().1 - 0.2).abs() < 1e-15);
        let f2 = "DATA:\n  - type: formula 2\n    wavelength_range: 0.3 2.5\n    coefficients: 0 1.03961212 0.00600069867 0.231792344 0.0200179144 1.01046945 103.560653\n";
        // Schott N-BK7 (formula 2 coefficients): n_d = 1.5168 at 587.6 nm.
        let s = parse(f2, "bk7").unwrap();
        assert!((s.at(587.56).unwrap().0 - 1.5168).abs() < 1e-4);
        assert_eq!(s.at(587.56).unwrap().1, 0.0);
    }

    #[test]
    fn bad_files_are_named() {
        assert!(parse("foo: 1", "x.yml")
            .unwrap_err()
            .contains("x.yml: no `DATA:`"));
        let e = parse(
            "DATA:\n  - type: formula 5\n    coefficients: 1 2\n",
            "x.yml",
        )
        .unwrap_err();
        assert!(
            e.contains("formula 5") && e.contains("not supported"),
            "{e}"
        );
        let e = parse(
            "DATA:\n  - type: tabulated nk\n    data: |\n        0.4 1.5\n",
            "x.yml",
        )
        .unwrap_err();
        assert!(e.contains("data line 1: 2 numbers, expected 3"), "{e}");
    }
}
