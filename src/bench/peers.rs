//! The external peers (benches/peers/peer.py: Mitsuba 3's LLVM backend and a vectorised
//! NumPy Cook–Torrance), run as subprocesses on the same directions in the same run.

use crate::batch::{read_npy_f32, write_npy_f32, Batch};
use std::path::{Path, PathBuf};
use std::process::Command;

/// One peer measurement, or why it was skipped.
#[derive(Debug, Clone, serde::Serialize)]
pub struct PeerRow {
    /// `mitsuba`, `numpy` or `memcpy`.
    pub name: String,
    /// The peer scenario (`beckmann`, `ggx`) and our matching scenario.
    pub scenario: String,
    /// Tuples per call.
    pub tuples: usize,
    /// Median tuples per second, when it ran.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub evals_per_s: Option<f64>,
    /// Why it did not run.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub skipped: Option<String>,
    /// The peer's BRDF (`tuples × 3`, from its last timed call), when it computes one:
    /// the bench judges it against the f64 reference, so a ratio is between equal BRDFs.
    #[serde(skip)]
    pub brdf: Option<Vec<f32>>,
    /// Max relative error of `brdf` against the f64 reference (set by the bench).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_rel_err: Option<f64>,
}

/// The default location of `peer.py`: `benches/peers/` of the source tree this binary was
/// built from, else of the current directory.
pub fn default_script() -> PathBuf {
    let built = Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/peers/peer.py");
    if built.exists() {
        built
    } else {
        PathBuf::from("benches/peers/peer.py")
    }
}

/// Runs `peer` (`mitsuba` or `numpy`) on the directions of `batch` (10 columns, N = +z)
/// for the peer scenario `scenario`, `repeats` timed calls.
pub fn run(script: &Path, peer: &str, scenario: &str, batch: &Batch, repeats: usize) -> PeerRow {
    run_with(script, peer, scenario, batch, repeats, &[])
}

/// [`run`] with more of peer.py's options (`--llvm-isa avx2`).
pub fn run_with(
    script: &Path,
    peer: &str,
    scenario: &str,
    batch: &Batch,
    repeats: usize,
    extra: &[&str],
) -> PeerRow {
    let mut row = PeerRow {
        name: peer.into(),
        scenario: scenario.into(),
        tuples: batch.len(),
        evals_per_s: None,
        skipped: None,
        brdf: None,
        max_rel_err: None,
    };
    let skip = |mut row: PeerRow, why: String| {
        row.skipped = Some(why);
        row
    };
    if !script.exists() {
        return skip(row, format!("{} not found", script.display()));
    }
    let dir = match tempfile::tempdir() {
        Ok(d) => d,
        Err(e) => return skip(row, format!("no temporary directory: {e}")),
    };
    let input = dir.path().join("tuples.npy");
    let out = dir.path().join("result.json");
    let check = dir.path().join("brdf.npy");
    if let Err(e) = write_npy_f32(&input, batch.as_slice(), batch.columns()) {
        return skip(row, format!("cannot write the peer's input: {e}"));
    }
    let status = Command::new("python3")
        .arg(script)
        .args([
            "--peer",
            peer,
            "--scenario",
            scenario,
            "--repeats",
            &repeats.to_string(),
        ])
        .arg("--input")
        .arg(&input)
        .arg("--out")
        .arg(&out)
        .arg("--check")
        .arg(&check)
        .args(extra)
        .output();
    let output = match status {
        Ok(o) => o,
        Err(e) => return skip(row, format!("python3 could not be started: {e}")),
    };
    let json: serde_json::Value = match std::fs::read_to_string(&out)
        .ok()
        .and_then(|s| serde_json::from_str(&s).ok())
    {
        Some(j) => j,
        None => {
            return skip(
                row,
                format!(
                    "no result from peer.py: {}",
                    String::from_utf8_lossy(&output.stderr).trim()
                ),
            )
        }
    };
    if let Some(why) = json.get("skipped").and_then(|s| s.as_str()) {
        return skip(row, why.to_string());
    }
    match json.get("evals_per_s").and_then(|v| v.as_f64()) {
        Some(v) => {
            row.evals_per_s = Some(v);
            row.brdf = read_npy_f32(&check)
                .ok()
                .filter(|(data, shape)| shape == &[batch.len() as u64, 3] && !data.is_empty())
                .map(|(data, _)| data);
            row
        }
        None => skip(row, format!("peer.py returned no evals_per_s: {json}")),
    }
}
