//! Every GLSL file includes what it uses: a name one file defines (a function, struct,
//! constant, macro, buffer or its members) and another uses must be defined in a file the
//! user reaches through its own `#include`s, so no file works only because `eval.comp`
//! happened to include its dependencies first. Also: each file has its include guard, the
//! includes form no circle, no name is defined in two files, and `glsl/` holds exactly the
//! files the kernel embeds (`gpu::kernel::SOURCES`).
//!
//! The check is lexical: comments are dropped and every identifier counts as a use, so a
//! local variable named like another file's global counts too (rename the local). The
//! feature macros (`HAS_*`, injected from Rust or derived in terms.glsl) are not checked.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// One GLSL file: the names it defines, the identifiers it uses and the files it includes.
#[derive(Debug, Default)]
struct Unit {
    defines: BTreeSet<String>,
    uses: BTreeSet<String>,
    includes: Vec<String>,
}

/// The text without `//` and `/* */` comments (line breaks kept).
fn strip_comments(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while !rest.is_empty() {
        if let Some(after) = rest.strip_prefix("//") {
            rest = after.find('\n').map_or("", |i| &after[i..]);
        } else if let Some(after) = rest.strip_prefix("/*") {
            let end = after.find("*/").map_or(after.len(), |i| i + 2);
            out.extend(after[..end].chars().filter(|&c| c == '\n'));
            rest = &after[end..];
        } else {
            let c = rest.chars().next().unwrap();
            out.push(c);
            rest = &rest[c.len_utf8()..];
        }
    }
    out
}

fn is_ident_char(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '_'
}

/// The identifiers of a text, in order.
fn identifiers(text: &str) -> Vec<&str> {
    text.split(|c: char| !is_ident_char(c))
        .filter(|t| t.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_'))
        .collect()
}

/// The last identifier of a declaration (`float merl[]` → `merl`).
fn declared_name(declaration: &str) -> Option<&str> {
    let head = declaration.split('[').next().unwrap_or("");
    identifiers(head).last().copied()
}

/// Parses one file's stripped text.
fn unit(text: &str) -> Unit {
    let text = strip_comments(text);
    let mut u = Unit::default();
    let lines: Vec<&str> = text.lines().collect();
    let mut i = 0;
    while i < lines.len() {
        let line = lines[i];
        let trimmed = line.trim_start();
        let words = identifiers(trimmed);
        if let Some(rest) = trimmed.strip_prefix("#include") {
            u.includes.push(rest.trim().trim_matches('"').to_string());
        } else if trimmed.starts_with("#define") {
            u.defines.insert(words[1].to_string());
        } else if line.starts_with("layout(") && !line.contains(") in;") {
            // A resource: `layout(...) uniform T name;` or a block `layout(...) buffer B {
            // members } [instance];`, whose members are global names without an instance.
            let mut block = line.to_string();
            if line.contains('{') {
                while !block.contains('}') {
                    i += 1;
                    block.push_str(lines[i]);
                }
                let (head, body) = block.split_once('{').unwrap();
                let (members, tail) = body.split_once('}').unwrap();
                let instance = tail.trim().trim_end_matches(';').trim();
                u.defines.insert(declared_name(head).unwrap().to_string());
                if instance.is_empty() {
                    for member in members.split(';').filter_map(declared_name) {
                        u.defines.insert(member.to_string());
                    }
                } else {
                    u.defines.insert(instance.to_string());
                }
            } else {
                // A specialization constant, `layout(constant_id = N) const T NAME = value;`:
                // the name is the word before the initializer, after the qualifier.
                let decl = block.trim_end().trim_end_matches(';');
                let qualifier_end = decl.find(')').map_or(0, |i| i + 1);
                let decl = match decl[qualifier_end..].split_once('=') {
                    Some((head, _)) => &decl[..qualifier_end + head.len()],
                    None => decl,
                };
                if let Some(name) = declared_name(decl) {
                    u.defines.insert(name.to_string());
                }
            }
        } else if !line.starts_with(|c: char| c.is_whitespace() || c == '#') && words.len() >= 2 {
            // File scope: `struct S`, `const T NAME = ...`, `shared T NAME`, `T name(...)`.
            match words[0] {
                "struct" => {
                    u.defines.insert(words[1].to_string());
                }
                "const" | "shared" if words.len() >= 3 => {
                    u.defines.insert(words[2].to_string());
                }
                _ => {
                    let after = &trimmed[trimmed.find(words[1]).unwrap() + words[1].len()..];
                    if after.trim_start().starts_with('(') && words[0] != "return" {
                        u.defines.insert(words[1].to_string());
                    }
                }
            }
        }
        i += 1;
    }
    u.defines
        .retain(|d| !d.starts_with("HAS_") && !d.starts_with("VKBRDF_"));
    u.uses = identifiers(&text).into_iter().map(str::to_string).collect();
    u
}

/// The files a file reaches through its includes (itself excluded), or the circle found.
fn reached(
    units: &BTreeMap<String, Unit>,
    file: &str,
    path: &mut Vec<String>,
    out: &mut BTreeSet<String>,
) -> Result<(), String> {
    for inc in &units[file].includes {
        if path.contains(inc) {
            return Err(format!("{} -> {inc}", path.join(" -> ")));
        }
        let Some(_) = units.get(inc) else {
            return Err(format!("{file} includes {inc}, which is not in glsl/"));
        };
        if out.insert(inc.clone()) {
            path.push(inc.clone());
            reached(units, inc, path, out)?;
            path.pop();
        }
    }
    Ok(())
}

/// Every violation of the rule in `units`, as readable lines.
fn violations(units: &BTreeMap<String, Unit>) -> Vec<String> {
    let mut problems = Vec::new();
    let mut owner: BTreeMap<&str, &str> = BTreeMap::new();
    for (file, u) in units {
        for d in &u.defines {
            if let Some(other) = owner.insert(d, file) {
                problems.push(format!("`{d}` is defined in both {other} and {file}"));
            }
        }
    }
    for (file, u) in units {
        let mut reach = BTreeSet::new();
        if let Err(circle) = reached(units, file, &mut vec![file.clone()], &mut reach) {
            problems.push(format!("include circle or unknown file: {circle}"));
            continue;
        }
        for name in &u.uses {
            let Some(&home) = owner.get(name.as_str()) else {
                continue;
            };
            if home != file && !reach.contains(home) {
                problems.push(format!(
                    "{file} uses `{name}` from {home} without including it"
                ));
            }
        }
    }
    problems
}

fn glsl_dir() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("glsl")
}

#[test]
fn every_glsl_file_includes_what_it_uses() {
    let mut units = BTreeMap::new();
    for entry in std::fs::read_dir(glsl_dir()).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        let text = std::fs::read_to_string(&path).unwrap();
        if let Some(stem) = name.strip_suffix(".glsl") {
            let guard = format!("VKBRDF_{}_GLSL", stem.to_uppercase());
            assert!(
                text.contains(&format!("#ifndef {guard}\n#define {guard}\n")),
                "{name} has no include guard {guard}"
            );
        }
        units.insert(name, unit(&text));
    }
    let embedded: BTreeSet<String> = vkbrdf::gpu::kernel::SOURCES
        .iter()
        .map(|(name, _)| name.to_string())
        .collect();
    let on_disk: BTreeSet<String> = units.keys().cloned().collect();
    assert_eq!(
        embedded, on_disk,
        "gpu::kernel::SOURCES and the files of glsl/"
    );
    // Names the parser must see, or the check would pass vacuously.
    for (file, name) in [
        ("frame_fields.glsl", "Frame"),
        ("frame_fields.glsl", "TINY_COS"),
        ("terms.glsl", "ggx_d"),
        ("bindings.glsl", "tuple_texels"),
        ("bindings.glsl", "materials"),
        ("bindings.glsl", "params"),
        ("math.glsl", "FLT_MIN"),
        ("evaluate.glsl", "evaluate"),
    ] {
        assert!(
            units[file].defines.contains(name),
            "{file} should define {name}"
        );
    }
    let problems = violations(&units);
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// The check can fail: a missing include, a circle and a name defined twice are seen.
#[test]
fn the_include_check_sees_what_is_missing() {
    let files = |a: &str, b: &str| {
        BTreeMap::from([
            ("a.glsl".to_string(), unit(a)),
            ("b.glsl".to_string(), unit(b)),
        ])
    };
    let lib = "struct Thing { float x; };\nconst float LIMIT = 1.0;\nfloat helper(float x) {\n    return x;\n}\nlayout(std430) buffer Out {\n    float out_values[];\n};\n";
    let user = "float f(Thing t) {\n    // helper(LIMIT) in a comment is not a use\n    return helper(t.x) + out_values[0];\n}\n";
    let missing = violations(&files(lib, user));
    assert_eq!(missing.len(), 3, "{missing:?}");
    assert!(missing.iter().any(|p| p.contains("`helper` from a.glsl")));
    assert!(missing.iter().any(|p| p.contains("`out_values`")));
    assert!(violations(&files(lib, &format!("#include \"a.glsl\"\n{user}"))).is_empty());
    let circle = violations(&files("#include \"b.glsl\"\n", "#include \"a.glsl\"\n"));
    assert!(circle.iter().any(|p| p.contains("circle")), "{circle:?}");
    let twice = violations(&files(lib, "const float LIMIT = 2.0;\n"));
    assert!(
        twice
            .iter()
            .any(|p| p.contains("`LIMIT` is defined in both")),
        "{twice:?}"
    );
}
