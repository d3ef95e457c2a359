//! The library's modules form layers (docs/ARCHITECTURE.md): no import cycle between
//! top-level modules, and no module imports one from a layer above its own. Read from the
//! source: every `crate::NAME` path in `src/NAME.rs` or `src/NAME/**` (comments stripped) is
//! an edge NAME → that module.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Lowest first; a module may import its own layer or any below (never above).
const LAYERS: &[&[&str]] = &[
    &["error", "cancel", "stats", "vector"],
    &["terms", "spectral"],
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
        "spectral_eval",
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

/// A source file's module path: `src/cpu/aniso.rs` is `cpu::aniso`, `src/cpu/mod.rs`
/// `cpu`, `src/lib.rs` the crate root (empty).
fn module_path(rel: &Path) -> Vec<String> {
    let mut segs: Vec<String> = rel
        .iter()
        .map(|c| c.to_string_lossy().trim_end_matches(".rs").to_string())
        .collect();
    if matches!(
        segs.last().map(String::as_str),
        Some("mod" | "lib" | "main")
    ) {
        segs.pop();
    }
    segs
}

/// The code of a file that builds the library: comments and the test module (which by
/// this project's convention closes the file) left out.
fn code_of(text: &str) -> String {
    let end = text.find("#[cfg(test)]").unwrap_or(text.len());
    text[..end]
        .lines()
        .map(|l| l.split("//").next().unwrap())
        .collect::<Vec<_>>()
        .join("\n")
}

/// The paths of a `use` tree (`a::{b, c::{d, e as f}, *}`), each with the name it binds.
fn use_tree(tree: &str, prefix: &[String], out: &mut Vec<(Vec<String>, String)>) {
    let tree = tree.trim();
    if let Some(open) = tree.find('{') {
        let mut base = prefix.to_vec();
        base.extend(
            tree[..open]
                .split("::")
                .map(str::trim)
                .filter(|s| !s.is_empty())
                .map(String::from),
        );
        let inner = &tree[open + 1..tree.rfind('}').unwrap()];
        let (mut depth, mut start) = (0, 0);
        for (i, ch) in inner.char_indices() {
            match ch {
                '{' => depth += 1,
                '}' => depth -= 1,
                ',' if depth == 0 => {
                    use_tree(&inner[start..i], &base, out);
                    start = i + 1;
                }
                _ => {}
            }
        }
        use_tree(&inner[start..], &base, out);
        return;
    }
    if tree.is_empty() {
        return;
    }
    let (path, alias) = match tree.split_once(" as ") {
        Some((p, a)) => (p, Some(a.trim().to_string())),
        None => (tree, None),
    };
    let mut segs = prefix.to_vec();
    segs.extend(path.split("::").map(|s| s.trim().to_string()));
    if segs.last().map(String::as_str) == Some("self") {
        segs.pop();
    }
    let bound = alias.unwrap_or_else(|| segs.last().cloned().unwrap_or_default());
    out.push((segs, bound));
}

/// File → the files whose items it uses: every `use` and every path in the code rooted at
/// `crate`, `super`, `self`, a module the file declares or a name a `use` bound, resolved
/// to the deepest module it names (a re-export is the re-exporting file's item). A `mod`
/// declaration is not an edge; a child's `super::` use of its parent's items is.
fn file_edges() -> Graph {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut paths = Vec::new();
    sources(&src, &mut paths);
    let modules: BTreeMap<Vec<String>, String> = paths
        .iter()
        .map(|p| {
            let rel = p.strip_prefix(&src).unwrap();
            (module_path(rel), rel.to_string_lossy().to_string())
        })
        .collect();
    let mut graph = Graph::new();
    for (own, file) in &modules {
        if file == "main.rs" {
            continue;
        }
        let code = code_of(&std::fs::read_to_string(src.join(file)).unwrap());
        let absolute = |segs: &[String], bound: &BTreeMap<String, Vec<String>>| {
            let first = segs.first()?.as_str();
            let mut abs = match first {
                "crate" => Vec::new(),
                "self" => own.clone(),
                "super" => own[..own.len().saturating_sub(1)].to_vec(),
                _ => {
                    let mut child = own.clone();
                    child.push(first.to_string());
                    if modules.contains_key(&child) {
                        own.clone()
                    } else {
                        let mut b = bound.get(first)?.clone();
                        b.extend(segs[1..].iter().cloned());
                        return Some(b);
                    }
                }
            };
            let rest = if first == "crate" || first == "self" || first == "super" {
                &segs[1..]
            } else {
                segs
            };
            let mut rest = rest;
            while rest.first().map(String::as_str) == Some("super") {
                abs.pop();
                rest = &rest[1..];
            }
            abs.extend(rest.iter().cloned());
            Some(abs)
        };
        // The `use` statements first: what they bind, and their edges.
        let mut bound: BTreeMap<String, Vec<String>> = BTreeMap::new();
        let mut targets: Vec<Vec<String>> = Vec::new();
        let mut rest = code.as_str();
        while let Some(i) = rest.find("use ") {
            let before = rest[..i].chars().last();
            let after = &rest[i + 4..];
            let end = after.find(';').unwrap_or(after.len());
            let tree_text = &after[..end];
            let is_tree = tree_text
                .chars()
                .all(|c| c.is_alphanumeric() || "_:{}, *\n\t".contains(c));
            if is_tree && before.is_none_or(|c| c.is_whitespace() || c == ';' || c == '}') {
                let mut tree = Vec::new();
                use_tree(&after[..end], &[], &mut tree);
                for (segs, name) in tree {
                    if let Some(abs) = absolute(&segs, &bound) {
                        bound.insert(name, abs.clone());
                        targets.push(abs);
                    }
                }
            }
            rest = &after[end..];
        }
        // Then every qualified path in the code.
        let bytes = code.as_bytes();
        let ident = |c: u8| c.is_ascii_alphanumeric() || c == b'_';
        let mut i = 0;
        while i < bytes.len() {
            if ident(bytes[i]) && (i == 0 || !(ident(bytes[i - 1]) || bytes[i - 1] == b'$')) {
                let mut j = i;
                let mut segs = Vec::new();
                loop {
                    let s = j;
                    while j < bytes.len() && ident(bytes[j]) {
                        j += 1;
                    }
                    segs.push(code[s..j].to_string());
                    if code[j..].starts_with("::")
                        && code[j + 2..].bytes().next().is_some_and(ident)
                    {
                        j += 2;
                    } else {
                        break;
                    }
                }
                if segs.len() > 1 {
                    if let Some(abs) = absolute(&segs, &bound) {
                        targets.push(abs);
                    }
                }
                i = j;
            } else {
                i += 1;
            }
        }
        let entry = graph.entry(file.clone()).or_default();
        for abs in targets {
            // The deepest module the path names.
            let to = (0..=abs.len())
                .rev()
                .find_map(|n| modules.get(&abs[..n]))
                .expect("the crate root is a module");
            if to != file && to != "lib.rs" {
                entry.insert(to.clone());
            }
        }
    }
    graph
}

/// The files still in a circle when the file-level check arrived (the architecture issue's
/// debt): the check fails on a circle through any other file, and on a file here that is no
/// longer in one (take it off the list), so the list only shrinks. Empty since the files of
/// `gpu/` left their circle: every circle now fails the check.
const FILES_STILL_IN_CIRCLES: &[&str] = &[];

#[test]
fn no_two_files_use_each_other_even_through_others() {
    let g = file_edges();
    let listed = |f: &str| {
        FILES_STILL_IN_CIRCLES.iter().any(|l| {
            if l.ends_with('/') {
                f.starts_with(l)
            } else {
                f == *l
            }
        })
    };
    let all = circles(&g);
    let in_circles: BTreeSet<&String> = all.iter().flatten().collect();
    let fixed: Vec<&&str> = FILES_STILL_IN_CIRCLES
        .iter()
        .filter(|l| {
            !in_circles.iter().any(|f| {
                if l.ends_with('/') {
                    f.starts_with(**l)
                } else {
                    f == *l
                }
            })
        })
        .collect();
    assert!(
        fixed.is_empty(),
        "no longer in a circle: take {fixed:?} off FILES_STILL_IN_CIRCLES"
    );
    let circles: Vec<BTreeSet<String>> = all
        .into_iter()
        .filter(|group| !group.iter().all(|f| listed(f)))
        .collect();
    assert!(
        g["cpu/aniso.rs"].contains("cpu/kernel.rs") || g["cpu/aniso.rs"].contains("cpu/lanes.rs"),
        "{:?}",
        g["cpu/aniso.rs"]
    );
    assert!(
        circles.is_empty(),
        "files that use each other (directly or through others), each group with one cycle:\n{}",
        circles
            .iter()
            .map(|group| {
                let sub: Graph = group
                    .iter()
                    .map(|f| (f.clone(), g[f].intersection(group).cloned().collect()))
                    .collect();
                format!("{:?}: {}", group, find_cycle(&sub).unwrap().join(" → "))
            })
            .collect::<Vec<_>>()
            .join("\n")
    );
}

/// The groups of nodes that reach each other (the strongly connected components with
/// more than one node).
fn circles(g: &Graph) -> Vec<BTreeSet<String>> {
    let reach = |from: &str| {
        let mut seen = BTreeSet::new();
        let mut stack = vec![from.to_string()];
        while let Some(n) = stack.pop() {
            for m in g.get(&n).into_iter().flatten() {
                if seen.insert(m.clone()) {
                    stack.push(m.clone());
                }
            }
        }
        seen
    };
    let reached: BTreeMap<&String, BTreeSet<String>> = g.keys().map(|n| (n, reach(n))).collect();
    let mut groups: Vec<BTreeSet<String>> = Vec::new();
    for n in g.keys() {
        if groups.iter().any(|grp| grp.contains(n)) || !reached[n].contains(n) {
            continue;
        }
        let group: BTreeSet<String> = reached[n]
            .iter()
            .filter(|m| reached.get(m).is_some_and(|r| r.contains(n)))
            .cloned()
            .collect();
        groups.push(group);
    }
    groups
}
