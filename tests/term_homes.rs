//! Each term's homes agree: its Rust file (`src/terms/<family>/<name>.rs`, its `NAME` and
//! `CITATION`) and its GLSL block in `glsl/terms.glsl` (`// term <family>/<name>:
//! <citation>`, functions named `<name>_...`), in the order of the family's list — so a
//! term added, renamed or re-cited in one engine and not the other fails here.

use std::path::Path;

const FAMILIES: [&str; 4] = ["d", "g", "f", "k"];

fn read(rel: &str) -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(rel))
        .unwrap_or_else(|e| panic!("{rel}: {e}"))
}

/// The term files a family's list names, in order (`Variant = code => name, ...;`).
fn family_list(family: &str) -> Vec<String> {
    read(&format!("src/terms/{family}/mod.rs"))
        .lines()
        .filter_map(|l| {
            let (head, rest) = l.split_once("=> ")?;
            // `Variant = 3 => name, …`: the code is a number.
            let code = head.split_once('=')?.1.trim();
            if code.is_empty() || !code.chars().all(|c| c.is_ascii_digit()) {
                return None;
            }
            let name = rest.split(',').next()?.trim();
            name.chars()
                .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
                .then(|| name.to_string())
        })
        .collect()
}

/// A `pub const X: &str = "...";` of a Rust file.
fn const_str(text: &str, name: &str) -> String {
    let key = format!("pub const {name}: &str = \"");
    let start = text.find(&key).unwrap_or_else(|| panic!("no {name}")) + key.len();
    text[start..start + text[start..].find('"').unwrap()].to_string()
}

/// The author–year pairs a citation names (`Walter et al. 2007`, `Cook & Torrance 1982`):
/// each work's first capitalised word and its year.
fn works(citation: &str) -> Vec<(String, String)> {
    citation
        .split(';')
        .filter_map(|w| {
            let year = w
                .split_whitespace()
                .find(|t| t.len() == 4 && t.chars().all(|c| c.is_ascii_digit()))?;
            let author = w
                .split_whitespace()
                .find(|t| t.starts_with(|c: char| c.is_ascii_uppercase()))?;
            Some((
                author
                    .trim_matches(|c: char| !c.is_alphanumeric())
                    .to_string(),
                year.to_string(),
            ))
        })
        .collect()
}

/// The GLSL blocks: (family/name, citation, the block's text).
fn glsl_blocks() -> Vec<(String, String, String)> {
    let text = read("glsl/terms.glsl");
    let mut blocks: Vec<(String, String, String)> = Vec::new();
    for line in text.lines() {
        if let Some(rest) = line.strip_prefix("// term ") {
            let (id, citation) = rest.split_once(": ").expect("`// term f/name: citation`");
            blocks.push((id.to_string(), citation.to_string(), String::new()));
        } else if line.starts_with("// =====") {
            blocks.push(("(divider)".into(), String::new(), String::new()));
        } else if let Some(b) = blocks.last_mut() {
            b.2.push_str(line);
            b.2.push('\n');
        }
    }
    blocks.retain(|b| b.0 != "(divider)");
    blocks
}

/// The functions a block of GLSL defines (a type, a name and `(` at the line's start).
fn functions(block: &str) -> Vec<String> {
    block
        .lines()
        .filter(|l| !l.starts_with(' ') && !l.starts_with('#') && !l.starts_with("//"))
        .filter_map(|l| {
            let mut words = l.split_whitespace();
            let _type = words.next()?;
            let name = words.next()?.split('(').next()?;
            l.contains('(').then(|| name.to_string())
        })
        .collect()
}

#[test]
fn every_term_has_one_rust_file_and_one_glsl_block_with_the_same_name_and_citation() {
    let blocks = glsl_blocks();
    let mut expected = Vec::new();
    for family in FAMILIES {
        for name in family_list(family) {
            let rust = read(&format!("src/terms/{family}/{name}.rs"));
            let citation = const_str(&rust, "CITATION");
            assert!(!const_str(&rust, "NAME").is_empty());
            let doc: String = rust
                .lines()
                .take_while(|l| l.starts_with("//!"))
                .collect::<Vec<_>>()
                .join(" ");
            for (author, year) in works(&citation) {
                assert!(
                    doc.contains(&author) && doc.contains(&year),
                    "{family}/{name}.rs: its doc does not cite {author} {year} (CITATION {citation:?})"
                );
            }
            expected.push((format!("{family}/{name}"), citation));
        }
    }
    assert!(expected.len() >= 19, "{expected:?}");
    let found: Vec<(String, String)> = blocks.iter().map(|b| (b.0.clone(), b.1.clone())).collect();
    assert_eq!(
        found, expected,
        "glsl/terms.glsl's `// term` blocks and the family lists with their CITATIONs"
    );
    // Each block's functions carry its name; no function named after a term sits outside
    // that term's block.
    let names: Vec<String> = expected
        .iter()
        .map(|(id, _)| id.split('/').nth(1).unwrap().to_string())
        .collect();
    for (id, _, text) in &blocks {
        let name = id.split('/').nth(1).unwrap();
        let fns = functions(text);
        if name != "none" {
            assert!(
                fns.iter().any(|f| f.starts_with(&format!("{name}_"))),
                "block {id} defines no `{name}_...` function: {fns:?}"
            );
        }
        for f in &fns {
            for other in names.iter().filter(|o| o.as_str() != name) {
                // `smith_...` is a prefix of `smith_fast_...`: the longer name is the owner.
                let owned_by_longer = names.iter().any(|l| {
                    l.len() > other.len()
                        && l.starts_with(other.as_str())
                        && f.starts_with(&format!("{l}_"))
                });
                assert!(
                    !f.starts_with(&format!("{other}_"))
                        || owned_by_longer
                        || f.starts_with(&format!("{name}_")),
                    "`{f}` is in block {id}, not in {other}'s"
                );
            }
        }
    }
}

/// The term names of every family list.
fn term_names() -> Vec<String> {
    FAMILIES
        .iter()
        .flat_map(|f| family_list(f))
        .filter(|n| n != "none")
        .collect()
}

/// The `(file, function)` pairs of GLSL files other than terms.glsl whose function is
/// named after a term (`<name>_...`): a term's form outside its block.
fn term_forms_outside_terms_glsl() -> Vec<(String, String)> {
    let names = term_names();
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("glsl");
    let mut found = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let file = path.file_name().unwrap().to_string_lossy().to_string();
        if file == "terms.glsl" {
            continue;
        }
        for f in functions(&std::fs::read_to_string(&path).unwrap()) {
            if names.iter().any(|n| f.starts_with(&format!("{n}_"))) {
                found.push((file.clone(), f));
            }
        }
    }
    found
}

/// Item 3 of "one home per term": a term's float64 and m 2^e forms (the two frames'
/// tiny-cosine paths) sit in its block beside the float32 form, not in models.glsl; and a
/// block that has one of the two has the other, so the frames stay in step.
#[test]
fn a_terms_f64_and_xf_forms_sit_in_its_block() {
    let outside = term_forms_outside_terms_glsl();
    assert!(
        outside.is_empty(),
        "functions named after a term outside glsl/terms.glsl: {outside:?}"
    );
    let mut with_both = 0;
    for (id, _, text) in glsl_blocks() {
        let fns = functions(&text);
        let f64s: Vec<String> = fns
            .iter()
            .filter_map(|f| f.strip_suffix("_f64").map(str::to_string))
            .collect();
        let xfs: Vec<String> = fns
            .iter()
            .filter_map(|f| f.strip_suffix("_xf").map(str::to_string))
            .collect();
        assert_eq!(
            f64s.is_empty(),
            xfs.is_empty(),
            "block {id}: float64 forms {f64s:?} but m 2^e forms {xfs:?}"
        );
        with_both += usize::from(!f64s.is_empty());
    }
    // Every D (GGX's are its Lambda's), every G but none, the conductor's F, every K.
    assert!(with_both >= 15, "{with_both} blocks have both forms");
}

/// The test can fail: a block out of place or re-cited is seen.
#[test]
fn the_comparison_sees_names_and_citations() {
    assert_eq!(
        works("Trowbridge & Reitz 1975; Walter et al. 2007"),
        vec![
            ("Trowbridge".to_string(), "1975".to_string()),
            ("Walter".to_string(), "2007".to_string())
        ]
    );
    assert_eq!(family_list("g").first().map(String::as_str), Some("none"));
    assert!(functions("float ggx_d(float a) {\n    return a;\n}\n").contains(&"ggx_d".to_string()));
    assert!(glsl_blocks().iter().any(|b| b.0 == "d/ggx"));
    assert!(term_names().contains(&"smith_fast".to_string()));
    // models.glsl's dispatchers are found by the same reader (and are not term forms).
    let models =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("glsl/models.glsl"))
            .unwrap();
    assert!(functions(&models).contains(&"microfacet_gk_f64".to_string()));
}
