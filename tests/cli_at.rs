//! `vkbrdf at`: angles in, f and the terms out, in the documented frame.

mod common;

use common::{path, stderr, vkbrdf};

fn json(args: &[&str]) -> serde_json::Value {
    let out = vkbrdf(args);
    assert!(out.status.success(), "{args:?}: {}", stderr(&out));
    serde_json::from_slice(&out.stdout).expect("JSON on stdout")
}

#[test]
fn lambert_is_diffuse_over_pi_at_every_direction() {
    let dir = tempfile::tempdir().unwrap();
    let m = dir.path().join("m.toml");
    std::fs::write(
        &m,
        "[[material]]\nname = \"matte\"\nmodel = \"lambert\"\ndiffuse = 0.5\n",
    )
    .unwrap();
    let doc = json(&[
        "at",
        "matte",
        "-m",
        path(&m),
        "--dir",
        "10,0,70,33",
        "--dir",
        "60,200,5,10",
        "--json",
    ]);
    let results = doc["results"].as_array().unwrap();
    assert_eq!(results.len(), 2);
    for r in results {
        for f in r["f"].as_array().unwrap() {
            // FORMULAS.md §5: Lambert is c_diff / π.
            assert!(
                (f.as_f64().unwrap() - 0.5 / std::f64::consts::PI).abs() < 1e-7,
                "{r}"
            );
        }
        assert_eq!(r["D"].as_f64(), Some(0.0));
    }
}

#[test]
fn angles_follow_the_documented_frame() {
    // θi = 60°, φi = 90°: L = (0, sin 60°, cos 60°) (φ from +x toward +y, N = +z).
    let doc = json(&["at", "gold", "--dir", "60,90,30,0", "--json"]);
    let l: Vec<f64> = doc["results"][0]["l"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    let want = [0.0, 60f64.to_radians().sin(), 0.5];
    for (a, b) in l.iter().zip(want) {
        assert!((a - b).abs() < 1e-12, "L = {l:?}");
    }
    // Rusinkiewicz (θh 0, θd 45, φd 90) is L at (45°, 90°) and V at (45°, −90°).
    let a = json(&["at", "gold", "--rus", "0,45,90", "--json"]);
    let b = json(&["at", "gold", "--dir", "45,90,45,-90", "--json"]);
    let fa = a["results"][0]["f"].as_array().unwrap();
    let fb = b["results"][0]["f"].as_array().unwrap();
    for (x, y) in fa.iter().zip(fb) {
        let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
        assert!((x - y).abs() <= 1e-6 * y.abs(), "{x} vs {y}");
    }
}

#[test]
fn default_directions_and_errors() {
    let out = vkbrdf(&["at", "gold"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success() && text.lines().count() >= 6, "{text}");
    for (args, needle) in [
        (vec!["at", "no-such-preset"], "no preset named"),
        (vec!["at", "gold", "--dir", "30,0,30"], "expected 4"),
        (vec!["at", "gold", "--dir", "30,0,30,nan"], "not an angle"),
        (vec!["at", "gold", "--rus", "1e9,0,0"], "not an angle"),
    ] {
        let out = vkbrdf(&args);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", stderr(&out));
        assert!(stderr(&out).contains(needle), "{args:?}: {}", stderr(&out));
    }
}
