//! The measured indices shipped with vkbrdf (refractiveindex.info database, CC0; sources in
//! `data/SOURCES.md`), by the names a materials file gives `ior`.

use super::index::IndexSpectrum;

/// `(name, what it is, the file's text)` of every shipped data set.
pub const DATASETS: &[(&str, &str, &str)] = &[
    (
        "au-johnson-christy",
        "gold, Johnson & Christy 1972",
        include_str!("data/au-johnson-christy.yml"),
    ),
    (
        "ag-johnson-christy",
        "silver, Johnson & Christy 1972",
        include_str!("data/ag-johnson-christy.yml"),
    ),
    (
        "cu-johnson-christy",
        "copper, Johnson & Christy 1972",
        include_str!("data/cu-johnson-christy.yml"),
    ),
    (
        "al-rakic",
        "aluminium, Rakić 1995",
        include_str!("data/al-rakic.yml"),
    ),
    (
        "sio2-malitson",
        "fused silica, Malitson 1965 (Sellmeier)",
        include_str!("data/sio2-malitson.yml"),
    ),
    (
        "h2o-hale-querry",
        "water, Hale & Querry 1973",
        include_str!("data/h2o-hale-querry.yml"),
    ),
];

/// The shipped data set `name`, or `None` when there is none of that name.
pub fn dataset(name: &str) -> Option<IndexSpectrum> {
    let (_, _, text) = DATASETS.iter().find(|d| d.0 == name)?;
    // The shipped files are fixed; `every_dataset_reads` proves each parses.
    Some(super::rii::parse(text, name).expect("shipped data set parses"))
}

/// The names, for messages.
pub fn names() -> String {
    DATASETS.iter().map(|d| d.0).collect::<Vec<_>>().join(", ")
}

#[cfg(test)]
mod tests {
    #[test]
    fn every_dataset_reads_and_covers_the_visible() {
        for (name, _, _) in super::DATASETS {
            let s = super::dataset(name).unwrap();
            let (lo, hi) = s.range();
            assert!(lo <= 360.0 && hi >= 830.0, "{name}: {lo}–{hi}");
        }
        // Johnson & Christy's gold at its 0.5486 µm row: n = 0.43, k = 2.455.
        let au = super::dataset("au-johnson-christy").unwrap();
        let (n, k) = au.at(548.6).unwrap();
        assert!(
            (n - 0.43).abs() < 1e-12 && (k - 2.455).abs() < 1e-12,
            "{n} {k}"
        );
    }
}
