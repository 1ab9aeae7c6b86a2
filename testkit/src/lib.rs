//! For the project's tests only: a test that needs something optional (Python packages, a
//! browser, the `../shared` fixtures) asks [`available`] whether to run. A skip is never
//! silent: it is printed and appended to the file `$DIT_GARMENT_SKIP_LOG` names, which
//! `.ci/run` prints after the tests (a passing test's printed output is hidden). Where the
//! environment sets `DIT_GARMENT_REQUIRE_<WHAT>` (`.ci/run` does after installing the thing),
//! a missing dependency fails the test instead.

use std::io::Write;

/// Whether the test `test` may run its part that needs `what` (`PYTHON`, `BROWSER`,
/// `SHARED`): `found` when true; otherwise the skip is recorded with `reason`, or the test
/// panics where `DIT_GARMENT_REQUIRE_<what>` is set.
pub fn available(test: &str, what: &str, found: bool, reason: &str) -> bool {
    if found {
        return true;
    }
    let require = format!("DIT_GARMENT_REQUIRE_{what}");
    assert!(
        std::env::var_os(&require).is_none(),
        "{test}: {reason}, and {require} is set"
    );
    eprintln!("SKIPPED {test}: {reason}");
    if let Some(log) = std::env::var_os("DIT_GARMENT_SKIP_LOG") {
        let line = format!("{test}\t{what}\t{reason}\n");
        let written = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(&log)
            .and_then(|mut f| f.write_all(line.as_bytes()));
        if let Err(e) = written {
            eprintln!("cannot record the skip in {}: {e}", log.to_string_lossy());
        }
    }
    false
}

/// Where Debian's assimp-testmodels puts CMU's BVH clips (`01_01.bvh`, `01_03.bvh`).
pub const CMU_CLIPS: &str = "/usr/share/assimp/models/BVH";

/// The CMU clip `name` for the test `test`, or `None` (the skip recorded, as [`available`])
/// where the package is not installed (`ASSIMP_TESTMODELS`).
pub fn cmu_clip(test: &str, name: &str) -> Option<std::path::PathBuf> {
    let path = std::path::Path::new(CMU_CLIPS).join(name);
    available(
        test,
        "ASSIMP_TESTMODELS",
        path.exists(),
        "CMU's clips come with Debian's assimp-testmodels (apt-get install assimp-testmodels)",
    )
    .then_some(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_found_dependency_runs_and_a_missing_one_is_logged() {
        assert!(available("t", "NOTHING_SET_HERE", true, "unused"));
        let dir = std::env::temp_dir().join(format!("testkit-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let log = dir.join("skips.tsv");
        // SAFETY: this test is the only one in this crate that touches the environment.
        unsafe { std::env::set_var("DIT_GARMENT_SKIP_LOG", &log) };
        assert!(!available("t", "NOTHING_SET_HERE", false, "not installed"));
        let text = std::fs::read_to_string(&log).unwrap();
        assert_eq!(text, "t\tNOTHING_SET_HERE\tnot installed\n");
        let required = std::panic::catch_unwind(|| {
            unsafe { std::env::set_var("DIT_GARMENT_REQUIRE_NOTHING_SET_HERE", "1") };
            available("t", "NOTHING_SET_HERE", false, "not installed")
        });
        assert!(
            required.is_err(),
            "a required dependency that is missing fails"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
