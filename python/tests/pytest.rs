//! Runs the Python package's tests (python/tests/, pytest) against the extension module this
//! `cargo test` has just built: the package's `.py` files and that cdylib are assembled in a
//! temporary directory put on `PYTHONPATH`, so the Python tests share the Rust tests' build
//! (no second build of the dependencies, as `pip install` would make).
//!
//! The interpreter is `REFRACT_PYTHON` or `python3`, and needs numpy and pytest (`.ci/run`
//! makes a virtual environment with them). Without them the test prints `skipped: ...` and
//! passes, except under `REFRACT_REQUIRE_PYTHON=1` (set by `.ci/run`), where it fails.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The interpreter to use, if it has numpy and pytest.
fn python() -> Result<String, String> {
    let python = std::env::var("REFRACT_PYTHON").unwrap_or_else(|_| "python3".to_owned());
    let probe = Command::new(&python)
        .args(["-c", "import numpy, pytest"])
        .output()
        .map_err(|err| format!("{python}: cannot run ({err})"))?;
    if probe.status.success() {
        Ok(python)
    } else {
        Err(format!(
            "{python} lacks numpy or pytest ({}); set REFRACT_PYTHON to an interpreter that has them",
            String::from_utf8_lossy(&probe.stderr).trim()
        ))
    }
}

/// The cdylib cargo built for this package (`lib_refract.so` or `.dylib`), in the profile
/// directory or its `deps/`.
fn extension_module(profile_dir: &Path) -> Option<PathBuf> {
    ["lib_refract.so", "lib_refract.dylib"]
        .iter()
        .flat_map(|name| [profile_dir.join(name), profile_dir.join("deps").join(name)])
        .filter(|p| p.exists())
        .max_by_key(|p| p.metadata().and_then(|m| m.modified()).ok())
}

#[test]
fn pytest_passes() {
    let required = std::env::var("REFRACT_REQUIRE_PYTHON").is_ok_and(|v| v == "1");
    let python = match python() {
        Ok(python) => python,
        Err(reason) if !required => {
            println!("skipped: {reason}");
            return;
        }
        Err(reason) => panic!("REFRACT_REQUIRE_PYTHON=1 but {reason}"),
    };
    // target/<profile>/deps/pytest-<hash> → target/<profile>
    let exe = std::env::current_exe().expect("the test's own path");
    let profile_dir = exe
        .parent()
        .and_then(Path::parent)
        .expect("the test runs from target/<profile>/deps");
    let module = extension_module(profile_dir).unwrap_or_else(|| {
        panic!(
            "no lib_refract.so under {}: cargo builds it with this test",
            profile_dir.display()
        )
    });

    let package_src = Path::new(env!("CARGO_MANIFEST_DIR")).join("refract");
    let site = tempfile::tempdir().expect("tempdir");
    let package = site.path().join("refract");
    std::fs::create_dir(&package).expect("create the package directory");
    for entry in std::fs::read_dir(&package_src).expect("python/refract") {
        let path = entry.expect("entry").path();
        if path.is_file() {
            let name = path.file_name().expect("a file name");
            std::fs::copy(&path, package.join(name)).expect("copy a package file");
        }
    }
    std::fs::copy(&module, package.join("_refract.abi3.so")).expect("copy the module");

    let mut pytest = Command::new(&python);
    pytest
        .args(["-m", "pytest", "-q", "-p", "no:cacheprovider"])
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests"))
        .env("PYTHONPATH", site.path())
        .env("PYTHONDONTWRITEBYTECODE", "1")
        .current_dir(site.path());
    // The CLI binary of this build, for the bit-identity test; `cargo test --workspace`
    // builds it (refract-cli's tests run it).
    let cli = profile_dir.join("refract");
    if cli.exists() {
        pytest.env("REFRACT_CLI", &cli);
    } else if required {
        panic!(
            "REFRACT_REQUIRE_PYTHON=1 but {} is missing: run `cargo test --workspace`",
            cli.display()
        );
    } else {
        println!(
            "note: {} missing; the bit-identity test skips",
            cli.display()
        );
    }
    let status = pytest.status().expect("run pytest");
    assert!(status.success(), "pytest failed: {status}");
}
