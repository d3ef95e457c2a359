//! `.ci/install-system` on fixture systems (`VKBRDF_SYSROOT` with `--dry-run`, so nothing is
//! installed): the C/C++ toolchain a minimal Debian lacks is installed, bookworm-backports is
//! derived only from the apt sources the machine has (one-line and deb822, options kept), a
//! machine with no source to extend gets a clear error, and no script under `.ci/` names a host.

use std::fs;
use std::path::Path;
use std::process::{Command, Output};

const SCRIPT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/.ci/install-system");

/// Every package the script checks, as it is named in the dpkg database.
const PACKAGES: &[&str] = &[
    "gcc",
    "g++",
    "libc6-dev",
    "pkg-config",
    "ca-certificates",
    "libvulkan1",
    "libvulkan-dev",
    "vulkan-tools",
    "vulkan-validationlayers",
    "libshaderc-dev",
    "glslang-dev",
    "spirv-tools",
    "glslc",
    "python3",
    "python3-venv",
    "valgrind",
];

/// A fixture system: bookworm's os-release, the given apt files (path under `etc/apt`,
/// contents) and a dpkg database holding `installed` (name, version).
fn sysroot(apt: &[(&str, &str)], installed: &[(&str, &str)]) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path();
    fs::create_dir_all(root.join("etc/apt/sources.list.d")).unwrap();
    fs::create_dir_all(root.join("var/lib/dpkg/updates")).unwrap();
    fs::write(
        root.join("etc/os-release"),
        "PRETTY_NAME=\"Debian GNU/Linux 12 (bookworm)\"\nVERSION_CODENAME=bookworm\nID=debian\n",
    )
    .unwrap();
    for (path, text) in apt {
        fs::write(root.join("etc/apt").join(path), text).unwrap();
    }
    let status: String = installed
        .iter()
        .map(|(name, version)| {
            format!(
                "Package: {name}\nStatus: install ok installed\nPriority: optional\n\
                 Section: misc\nMaintainer: none\nArchitecture: amd64\nVersion: {version}\n\
                 Description: fixture\n\n"
            )
        })
        .collect();
    fs::write(root.join("var/lib/dpkg/status"), status).unwrap();
    dir
}

/// Runs the script on `root` with `args`.
fn run(root: &Path, args: &[&str]) -> Output {
    Command::new("bash")
        .arg(SCRIPT)
        .args(args)
        .env("VKBRDF_SYSROOT", root)
        .output()
        .unwrap()
}

fn text(out: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// The `missing:` line of a dry run, split into package names.
fn missing(stdout: &str) -> Vec<String> {
    let line = stdout
        .lines()
        .find_map(|l| l.strip_prefix("missing:"))
        .unwrap_or_else(|| panic!("no `missing:` line in\n{stdout}"));
    line.split_whitespace().map(str::to_string).collect()
}

const BOOKWORM_LIST: &str = "deb file:/srv/debian bookworm main\n";

#[test]
fn minimal_debian_gets_the_c_toolchain_and_ca_certificates() {
    // debootstrap --variant=minbase has none of these: without gcc, cargo stops at
    // "linker `cc` not found"; without ca-certificates it cannot fetch crates.
    let root = sysroot(&[("sources.list", BOOKWORM_LIST)], &[]);
    let out = run(root.path(), &["--dry-run"]);
    let (stdout, stderr) = text(&out);
    assert_eq!(out.status.code(), Some(0), "{stdout}{stderr}");
    let need = missing(&stdout);
    for p in ["gcc", "g++", "libc6-dev", "pkg-config", "ca-certificates"] {
        assert!(need.iter().any(|n| n == p), "{p} not in {need:?}");
    }
    assert_eq!(
        need.iter().filter(|n| *n == "mesa-vulkan-drivers").count(),
        1,
        "{need:?}"
    );
}

#[test]
fn complete_system_is_left_alone_and_silent() {
    let mut installed: Vec<(&str, &str)> = PACKAGES.iter().map(|p| (*p, "1.0")).collect();
    installed.push(("mesa-vulkan-drivers", "25.0.7-2~bpo12+1"));
    // No apt source at all: with nothing to install, none is needed.
    let root = sysroot(&[], &installed);
    let out = run(root.path(), &[]);
    let (stdout, stderr) = text(&out);
    assert_eq!(out.status.code(), Some(0), "{stdout}{stderr}");
    assert_eq!((stdout.as_str(), stderr.as_str()), ("", ""));
}

#[test]
fn bookworm_mesa_22_asks_for_backports_mesa() {
    let mut installed: Vec<(&str, &str)> = PACKAGES.iter().map(|p| (*p, "1.0")).collect();
    installed.push(("mesa-vulkan-drivers", "22.3.6-1+deb12u1"));
    let root = sysroot(&[("sources.list", BOOKWORM_LIST)], &installed);
    let out = run(root.path(), &["--dry-run"]);
    let (stdout, stderr) = text(&out);
    assert_eq!(out.status.code(), Some(0), "{stdout}{stderr}");
    assert_eq!(missing(&stdout), ["mesa-vulkan-drivers"]);
}

#[test]
fn backports_come_from_the_one_line_bookworm_source_with_its_options() {
    let list = "# a comment: deb file:/srv/commented bookworm main\n\
                deb file:/srv/security bookworm-security main\n\
                deb-src file:/srv/src bookworm main\n\
                deb [ signed-by=/usr/share/keyrings/k.gpg arch=amd64 ] file:/srv/debian bookworm main contrib\n";
    let root = sysroot(&[("sources.list", list)], &[]);
    let out = run(root.path(), &["--dry-run"]);
    let (stdout, stderr) = text(&out);
    assert_eq!(out.status.code(), Some(0), "{stdout}{stderr}");
    assert!(
        stdout.contains("sources.list.d/vkbrdf-backports.list:\n"),
        "{stdout}"
    );
    assert!(
        stdout.contains(
            "\ndeb [ signed-by=/usr/share/keyrings/k.gpg arch=amd64 ] file:/srv/debian bookworm-backports main\n"
        ),
        "{stdout}"
    );
}

#[test]
fn backports_come_from_the_deb822_bookworm_stanza_with_its_fields() {
    let sources = "Types: deb\nURIs: file:/srv/old\nSuites: bookworm\nComponents: main\nEnabled: no\n\n\
                   # the security archive\n\
                   Types: deb\nURIs: file:/srv/security\nSuites: bookworm-security\nComponents: main\n\n\
                   Types: deb deb-src\nURIs: file:/srv/debian\nSuites: bookworm bookworm-updates\n\
                   Components: main contrib\nSigned-By: /usr/share/keyrings/debian-archive-keyring.gpg\n";
    let root = sysroot(&[("sources.list.d/debian.sources", sources)], &[]);
    let out = run(root.path(), &["--dry-run"]);
    let (stdout, stderr) = text(&out);
    assert_eq!(out.status.code(), Some(0), "{stdout}{stderr}");
    let expected = "sources.list.d/vkbrdf-backports.sources:\n\
                    Types: deb\nSuites: bookworm-backports\nComponents: main\n\
                    URIs: file:/srv/debian\n\
                    Signed-By: /usr/share/keyrings/debian-archive-keyring.gpg\n";
    assert!(stdout.ends_with(expected), "{stdout}");
}

#[test]
fn configured_backports_is_not_added_again() {
    let sources = "Types: deb\nURIs: file:/srv/debian\nSuites: bookworm bookworm-backports\nComponents: main\n";
    let root = sysroot(&[("sources.list.d/debian.sources", sources)], &[]);
    let out = run(root.path(), &["--dry-run"]);
    let (stdout, stderr) = text(&out);
    assert_eq!(out.status.code(), Some(0), "{stdout}{stderr}");
    assert!(
        stdout.contains("bookworm-backports: already configured"),
        "{stdout}"
    );
    assert!(!stdout.contains("would add"), "{stdout}");
}

#[test]
fn no_configured_source_is_a_clear_error() {
    // Nothing at all, a commented-out line, a disabled stanza: no source to use.
    for apt in [
        vec![],
        vec![("sources.list", "# deb file:/srv/debian bookworm main\n")],
        vec![(
            "sources.list.d/debian.sources",
            "Types: deb\nURIs: file:/srv/debian\nSuites: bookworm\nComponents: main\nEnabled: no\n",
        )],
    ] {
        let root = sysroot(&apt, &[]);
        let out = run(root.path(), &["--dry-run"]);
        let (stdout, stderr) = text(&out);
        assert_eq!(out.status.code(), Some(2), "{apt:?}: {stdout}{stderr}");
        assert!(
            stderr.contains("apt has no enabled package source") && stderr.contains("gcc"),
            "{apt:?}: {stderr}"
        );
    }
}

#[test]
fn no_bookworm_source_to_extend_is_a_clear_error() {
    let root = sysroot(
        &[(
            "sources.list",
            "deb file:/srv/security bookworm-security main\n",
        )],
        &[],
    );
    let out = run(root.path(), &["--dry-run"]);
    let (stdout, stderr) = text(&out);
    assert_eq!(out.status.code(), Some(2), "{stdout}{stderr}");
    assert!(
        stderr.contains("no apt source for the suite 'bookworm' to extend"),
        "{stderr}"
    );
    assert!(!stdout.contains("would add"), "{stdout}");
}

#[test]
fn ci_scripts_name_no_host() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join(".ci");
    for entry in fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        let text = fs::read_to_string(&path).unwrap();
        for (n, line) in text.lines().enumerate() {
            assert!(
                !line.contains("http://") && !line.contains("https://"),
                "{}:{}: names a web address: {line}",
                path.display(),
                n + 1
            );
        }
    }
}
