//! The library's modules form layers (docs/ARCHITECTURE.md): no import cycle between
//! top-level modules, and no module imports one from a layer above its own. Read from the
//! source: every `crate::NAME` path in `src/NAME.rs` or `src/NAME/**` (comments stripped) is
//! an edge NAME → that module.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Lowest first; a module may import its own layer or any below (never above).
const LAYERS: &[&[&str]] = &[
    &["error", "cancel", "stats", "vector"],
    &["atomic", "material"],
    &["batch", "directions"],
    &["backend", "precision", "sample"],
    &["reference", "features", "importance"],
    &["gpu", "cpu"],
    &[
        "table",
        "check",
        "stress",
        "bench",
        "stream",
        "backend_choice",
        "fit",
    ],
];

fn layer_of(module: &str) -> usize {
    LAYERS
        .iter()
        .position(|l| l.contains(&module))
        .unwrap_or_else(|| panic!("module `{module}` has no layer in LAYERS (add it)"))
}

fn sources(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            sources(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// Top-level module → the top-level modules it names through `crate::`.
fn edges() -> BTreeMap<String, BTreeSet<String>> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    sources(&src, &mut files);
    let mut edges: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for f in files {
        let rel = f.strip_prefix(&src).unwrap();
        let first = rel
            .components()
            .next()
            .unwrap()
            .as_os_str()
            .to_string_lossy();
        let module = first.trim_end_matches(".rs").to_string();
        // The binary's front end (main, cli) and the crate root sit above every layer.
        if ["main", "lib", "cli"].contains(&module.as_str()) {
            continue;
        }
        let text = std::fs::read_to_string(&f).unwrap();
        let entry = edges.entry(module.clone()).or_default();
        for line in text.lines() {
            let code = line.split("//").next().unwrap();
            for (i, _) in code.match_indices("crate::") {
                let name: String = code[i + 7..]
                    .chars()
                    .take_while(|c| c.is_ascii_lowercase() || *c == '_')
                    .collect();
                if !name.is_empty() && name != module {
                    entry.insert(name);
                }
            }
        }
    }
    edges
}

#[test]
fn no_module_imports_a_layer_above_its_own() {
    let mut wrong = Vec::new();
    for (from, tos) in edges() {
        for to in tos {
            if layer_of(&to) > layer_of(&from) {
                wrong.push(format!(
                    "{from} (layer {}) → {to} (layer {})",
                    layer_of(&from),
                    layer_of(&to)
                ));
            }
        }
    }
    assert!(
        wrong.is_empty(),
        "imports above their layer:\n{}",
        wrong.join("\n")
    );
}

type Graph = BTreeMap<String, BTreeSet<String>>;

/// A cycle of `edges`, if there is one (depth-first search with colours: a node reached
/// again while still on the path closes a cycle).
fn find_cycle(edges: &Graph) -> Option<Vec<String>> {
    fn visit(
        n: &str,
        edges: &Graph,
        colour: &mut BTreeMap<String, u8>,
        path: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        colour.insert(n.to_string(), 1);
        path.push(n.to_string());
        for m in edges.get(n).into_iter().flatten() {
            match colour.get(m.as_str()).copied().unwrap_or(0) {
                1 => {
                    let start = path.iter().position(|p| p == m).unwrap();
                    let mut cycle = path[start..].to_vec();
                    cycle.push(m.clone());
                    return Some(cycle);
                }
                0 => {
                    if let Some(c) = visit(m, edges, colour, path) {
                        return Some(c);
                    }
                }
                _ => {}
            }
        }
        path.pop();
        colour.insert(n.to_string(), 2);
        None
    }
    let mut colour = BTreeMap::new();
    for n in edges.keys() {
        if colour.get(n.as_str()).copied().unwrap_or(0) == 0 {
            if let Some(c) = visit(n, edges, &mut colour, &mut Vec::new()) {
                return Some(c);
            }
        }
    }
    None
}

#[test]
fn the_module_graph_has_no_cycle() {
    if let Some(c) = find_cycle(&edges()) {
        panic!("import cycle: {}", c.join(" → "));
    }
}

/// The checks can fail: the reader sees real imports, and the cycle finder finds the
/// cycles this project had (material → table → material, material ↔ precision).
#[test]
fn the_checks_see_real_imports_and_cycles() {
    let e = edges();
    assert!(e["table"].contains("backend"), "{e:?}");
    assert!(e["gpu"].contains("features"), "{e:?}");
    let graph = |pairs: &[(&str, &str)]| {
        let mut g = Graph::new();
        for (a, b) in pairs {
            g.entry(a.to_string()).or_default().insert(b.to_string());
        }
        g
    };
    let old = graph(&[
        ("material", "table"),
        ("table", "batch"),
        ("batch", "material"),
    ]);
    assert_eq!(
        find_cycle(&old).map(|c| c.len()),
        Some(4),
        "{:?}",
        find_cycle(&old)
    );
    assert!(find_cycle(&graph(&[
        ("material", "precision"),
        ("precision", "material")
    ]))
    .is_some());
    assert!(find_cycle(&graph(&[("table", "material"), ("batch", "material")])).is_none());
}
