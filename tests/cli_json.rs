//! `--json` on the summaries of `vkbrdf check` and `vkbrdf stress`: standard output is one
//! JSON document a script can parse (the prose goes to standard error), with the figures the
//! text reports.

mod common;

use serde_json::Value;

fn json_of(args: &[&str], envs: &[(&str, &str)]) -> (Option<i32>, Value, String) {
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_vkbrdf"))
        .args(args)
        .envs(envs.iter().copied())
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout).to_string();
    let doc: Value = serde_json::from_str(&stdout).unwrap_or_else(|e| {
        panic!(
            "stdout is not JSON ({e}):\n{stdout}\n{}",
            common::stderr(&o)
        )
    });
    (o.status.code(), doc, common::stderr(&o))
}

#[test]
fn check_json_parses_and_carries_the_figures() {
    let (code, doc, err) = json_of(
        &[
            "check",
            "--backend",
            "reference",
            "--filter",
            "lambert",
            "--tuples",
            "50",
            "--json",
        ],
        &[],
    );
    assert_eq!(code, Some(0), "{err}");
    // The table went to standard error.
    assert!(err.contains("lambert"), "{err}");
    let combos = doc["combinations"].as_array().unwrap();
    assert_eq!(combos.len(), 1);
    assert_eq!(combos[0]["name"], "lambert");
    assert_eq!(combos[0]["tuples"], 50);
    assert_eq!(combos[0]["pass"], true);
    assert!(combos[0]["max_rel"].as_f64().unwrap() <= 6e-8);
    assert!(combos[0]["column_max_rel"]["brdf_r"].is_number());
    assert_eq!(doc["passed"], 1);
    assert_eq!(doc["failed"], 0);
    assert_eq!(doc["ok"], true);
    assert_eq!(doc["tuples_per_combination"], 50);
    assert!(doc["skipped"].as_array().unwrap().is_empty());
}

#[test]
fn check_json_lists_measured_combinations_skipped_without_f64() {
    if common::vulkan().is_none() {
        return;
    }
    let (code, doc, err) = json_of(
        &["check", "--filter", "merl", "--tuples", "100", "--json"],
        &[("VKBRDF_DISABLE_FLOAT64", "1")],
    );
    assert_eq!(code, Some(0), "{err}");
    let skipped = doc["skipped"].as_array().unwrap();
    let names: Vec<&str> = skipped
        .iter()
        .map(|s| s["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["merl nearest", "merl linear"]);
    assert!(
        skipped[0]["reason"]
            .as_str()
            .unwrap()
            .contains("shaderFloat64"),
        "{doc}"
    );
    // With f64, they run and pass.
    let (code, doc, err) = json_of(
        &["check", "--filter", "merl", "--tuples", "500", "--json"],
        &[],
    );
    assert_eq!(code, Some(0), "{err}");
    assert_eq!(doc["passed"], 2, "{doc}");
}

#[test]
fn stress_json_parses_and_carries_the_policy() {
    let (code, doc, err) = json_of(
        &["stress", "-n", "400", "--backend", "reference", "--json"],
        &[],
    );
    assert_eq!(code, Some(0), "{err}");
    assert!(
        err.contains("Stress") || err.contains("stress tuples"),
        "{err}"
    );
    let b = &doc["backends"].as_array().unwrap()[0];
    assert_eq!(b["tuples"], 400);
    assert_eq!(b["policy_holds"], true);
    assert_eq!(b["non_finite"], 0);
    assert_eq!(b["invalid"]["backend"], b["invalid"]["reference"]);
    let errors = b["errors"].as_array().unwrap();
    assert!(!errors.is_empty());
    assert!(errors
        .iter()
        .all(|e| e["max_rel"].is_number() && e["regime"].is_string()));
    assert_eq!(doc["ok"], true);
    assert_eq!(doc["tuples"], 400);
}
