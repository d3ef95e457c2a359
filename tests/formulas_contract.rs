//! The contract (`docs/FORMULAS.md`, the repository's own and only copy) checked for the
//! structure code, tests and docs rely on — sections 1–9 in order, each with text, a
//! non-empty table in each of §1–§6 — and against the code: every name the first column of
//! §2–§5 defines is a term the materials parser knows (`ALL` and `toml_name` of each term
//! family in `src/terms/`), and every term the parser knows is defined there, so
//! the two cannot drift apart unnoticed. The section numbers and names are what code, tests
//! and docs cite ("FORMULAS.md §n").

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// One `## n. Title` section: its title, the first-column names of its tables (in order,
/// duplicates kept) and the names of its `` - `name`: `` definition items.
#[derive(Debug, Default, PartialEq)]
struct Section {
    title: String,
    table_names: Vec<String>,
    defined_names: Vec<String>,
    tables: usize,
    body_lines: usize,
}

/// The contents of the first table cell of `line` (a line starting with `|`), ending at the
/// first `|` outside a code span (cells hold spans such as `` `L/|L|` ``).
fn first_cell(line: &str) -> &str {
    let rest = &line[1..];
    let mut in_code = false;
    for (i, ch) in rest.char_indices() {
        match ch {
            '`' => in_code = !in_code,
            '|' if !in_code => return rest[..i].trim(),
            _ => {}
        }
    }
    rest.trim()
}

/// The name a first cell defines: its first code span, plus a qualifier written right after
/// it (`` `beckmann` anisotropic, … `` → `beckmann anisotropic`); a citation in parentheses
/// is not part of the name. A cell without a code span is its own name.
fn cell_name(cell: &str) -> String {
    let Some(start) = cell.find('`') else {
        return cell.to_string();
    };
    let Some(len) = cell[start + 1..].find('`') else {
        return cell.to_string();
    };
    let name = &cell[start + 1..start + 1 + len];
    let after = cell[start + 2 + len..].trim_start();
    let qualifier: String = after
        .chars()
        .take_while(|c| c.is_alphanumeric() || *c == ' ' || *c == '-')
        .collect();
    let qualifier = qualifier.trim();
    if qualifier.is_empty() {
        name.to_string()
    } else {
        format!("{name} {qualifier}")
    }
}

/// Parses `## n. Title` sections with their table names and definition items.
fn parse(text: &str) -> BTreeMap<u32, Section> {
    let mut sections = BTreeMap::new();
    let mut current: Option<u32> = None;
    // Within a table: 0 = the header row is next, 1 = the separator, 2 = data rows.
    let mut table_row: Option<u8> = None;
    for line in text.lines() {
        if let Some(heading) = line.strip_prefix("## ") {
            table_row = None;
            let (num, title) = heading
                .split_once(". ")
                .unwrap_or_else(|| panic!("section heading not `## n. Title`: {line:?}"));
            let num: u32 = num
                .trim()
                .parse()
                .unwrap_or_else(|_| panic!("section number not an integer: {line:?}"));
            let previous = sections.insert(
                num,
                Section {
                    title: title.trim().to_string(),
                    ..Section::default()
                },
            );
            assert!(previous.is_none(), "section {num} appears twice");
            current = Some(num);
            continue;
        }
        let Some(section) = current.and_then(|n| sections.get_mut(&n)) else {
            continue;
        };
        if !line.trim().is_empty() {
            section.body_lines += 1;
        }
        if line.starts_with('|') {
            match table_row {
                None => {
                    section.tables += 1;
                    table_row = Some(1);
                }
                Some(1) => {
                    assert!(
                        line.starts_with("|---") || line.starts_with("|:--"),
                        "table without a separator row: {line:?}"
                    );
                    table_row = Some(2);
                }
                Some(_) => section.table_names.push(cell_name(first_cell(line))),
            }
            continue;
        }
        table_row = None;
        if let Some(item) = line.strip_prefix("- `") {
            if let Some(end) = item.find('`') {
                if item[end + 1..].starts_with(':') {
                    section.defined_names.push(item[..end].to_string());
                }
            }
        }
    }
    sections
}

/// Every disagreement between `repo` and `source`, one line each; empty when they agree.
fn differences(repo: &BTreeMap<u32, Section>, source: &BTreeMap<u32, Section>) -> Vec<String> {
    let mut out = Vec::new();
    for (num, src) in source {
        let Some(ours) = repo.get(num) else {
            out.push(format!(
                "§{num} ({}) is missing from docs/FORMULAS.md",
                src.title
            ));
            continue;
        };
        if ours.title != src.title {
            out.push(format!(
                "§{num} title: docs has {:?}, source has {:?}",
                ours.title, src.title
            ));
        }
        for (what, a, b) in [
            ("table names", &ours.table_names, &src.table_names),
            ("defined names", &ours.defined_names, &src.defined_names),
        ] {
            let (mut a, mut b) = (a.clone(), b.clone());
            a.sort();
            b.sort();
            if a != b {
                let only_docs: Vec<_> = a.iter().filter(|n| !b.contains(n)).collect();
                let only_source: Vec<_> = b.iter().filter(|n| !a.contains(n)).collect();
                out.push(format!(
                    "§{num} {what} differ: only in docs {only_docs:?}, only in the source {only_source:?} (docs {a:?}, source {b:?})"
                ));
            }
        }
    }
    for (num, ours) in repo {
        if !source.contains_key(num) {
            out.push(format!("§{num} ({}) is not in the source", ours.title));
        }
    }
    out
}

fn repo_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("reading {}: {e}", path.display()))
}

/// What the repository copy must hold on its own: sections 1–9 in order, each with text, a
/// non-empty table in each of §1–§6, §8 and §9, and the names the code dispatches on.
fn check_structure(repo: &BTreeMap<u32, Section>) {
    let numbers: Vec<u32> = repo.keys().copied().collect();
    assert_eq!(
        numbers,
        (1..=9).collect::<Vec<_>>(),
        "docs/FORMULAS.md sections"
    );
    for (num, s) in repo {
        assert!(!s.title.is_empty(), "§{num} has no title");
        assert!(s.body_lines > 0, "§{num} is empty");
        if *num != 7 {
            assert!(s.tables >= 1, "§{num} ({}) has no table", s.title);
            assert!(
                !s.table_names.is_empty(),
                "§{num} ({}) has an empty table",
                s.title
            );
        }
    }
    let has = |num: u32, name: &str| repo[&num].table_names.iter().any(|n| n == name);
    for (num, names) in [
        (2, &["gaussian", "beckmann", "ggx", "blinn", "charlie"][..]),
        (
            3,
            &[
                "none",
                "cook-torrance",
                "smith",
                "smith-correlated",
                "schlick-smith",
                "neubelt",
                "smith-fast",
            ][..],
        ),
        (4, &["none", "dielectric", "conductor", "schlick"][..]),
        (5, &["seed", "cook-torrance-1982", "modern"][..]),
        (
            6,
            &[
                "lambert",
                "phong",
                "blinn-phong",
                "rtr",
                "ward",
                "cook-torrance",
                "htsg",
            ][..],
        ),
        (
            8,
            &[
                "f", "ρ_dd", "F", "G", "S", "S1", "K(θ)", "σ", "g", "D", "ρ_s",
            ][..],
        ),
        (
            9,
            &[
                "η(λ)",
                "interpolation",
                "formula 1",
                "formula 2",
                "F(λ, c)",
                "up-sampling",
                "XYZ",
                "sRGB",
                "ΔE*ab",
                "mitsuba",
                "filament",
            ][..],
        ),
    ] {
        for name in names {
            assert!(
                has(num, name),
                "§{num} lacks `{name}`: {:?}",
                repo[&num].table_names
            );
        }
    }
}

#[test]
fn the_contract_has_its_sections_and_names() {
    let repo = parse(&read(&repo_root().join("docs/FORMULAS.md")));
    check_structure(&repo);
}

#[test]
fn the_contract_and_the_code_define_the_same_terms() {
    use vkbrdf::material::{Convention, DistributionKind, FresnelKind, Geometry};
    let repo = parse(&read(&repo_root().join("docs/FORMULAS.md")));
    let code: [(u32, Vec<&str>); 4] = [
        (
            2,
            DistributionKind::ALL
                .iter()
                .map(|d| d.toml_name())
                .collect(),
        ),
        (3, Geometry::ALL.iter().map(|g| g.toml_name()).collect()),
        (4, FresnelKind::ALL.iter().map(|f| f.toml_name()).collect()),
        (5, Convention::ALL.iter().map(|c| c.toml_name()).collect()),
    ];
    for (num, names) in code {
        // §2 also has anisotropic rows (`beckmann anisotropic`): the same terms.
        let table: Vec<String> = repo[&num]
            .table_names
            .iter()
            .map(|n| n.split(' ').next().unwrap_or(n).to_string())
            .collect();
        for n in &names {
            assert!(
                table.iter().any(|t| t == n),
                "§{num} does not define `{n}`, which the code knows: {table:?}"
            );
        }
        for t in &table {
            assert!(
                names.contains(&t.as_str()),
                "§{num} defines `{t}`, which the code does not know: {names:?}"
            );
        }
    }
}

/// The comparison itself catches a renamed term, a term moved to another section, a
/// dropped row and a changed title (so the test above cannot pass by parsing nothing).
#[test]
fn a_disagreement_is_reported() {
    let text = read(&repo_root().join("docs/FORMULAS.md"));
    let base = parse(&text);
    assert!(differences(&base, &base).is_empty());
    assert_eq!(
        cell_name("`beckmann` anisotropic, `m = [mx, my]`"),
        "beckmann anisotropic"
    );
    assert_eq!(cell_name("`gaussian` (Torrance–Sparrow 1967)"), "gaussian");
    assert_eq!(first_cell("| `l, v, n` | `L/|L|` | x |"), "`l, v, n`");

    let renamed = text.replacen("| `schlick-smith` (", "| `schlick-smyth` (", 1);
    assert_ne!(renamed, text);
    let d = differences(&parse(&renamed), &base);
    assert!(d.len() == 1 && d[0].contains("schlick-smyth"), "{d:?}");

    let charlie_row = text
        .lines()
        .find(|l| l.starts_with("| `charlie`"))
        .expect("charlie row");
    let dropped = text.replacen(&format!("{charlie_row}\n"), "", 1);
    let d = differences(&parse(&dropped), &base);
    assert!(d.len() == 1 && d[0].starts_with("§2 table names"), "{d:?}");

    // The same row moved from §2 to §3's table: both sections disagree.
    let moved = dropped.replacen(
        "| `none` | 1 |\n",
        &format!("| `none` | 1 |\n{charlie_row}\n"),
        1,
    );
    let d = differences(&parse(&moved), &base);
    assert!(
        d.iter().any(|l| l.starts_with("§2"))
            && d.iter()
                .any(|l| l.starts_with("§3") && l.contains("charlie")),
        "{d:?}"
    );

    let retitled = text.replacen("## 5. Conventions", "## 5. Convention", 1);
    let d = differences(&parse(&retitled), &base);
    assert!(d.len() == 1 && d[0].starts_with("§5 title"), "{d:?}");

    let lambda = text.replacen("- `ggx`: `Λ", "- `trowbridge`: `Λ", 1);
    let d = differences(&parse(&lambda), &base);
    assert!(d.len() == 1 && d[0].contains("defined names"), "{d:?}");
}
