//! `dit-garment regress`: the physics regression suite as a table and JSON; exits non-zero if
//! a scenario fails.

use anyhow::{Result, bail};
use regress::run as run_suite;
use serde_json::json;

use crate::cli::RegressArgs;
use files::write_json;

pub fn run(args: &RegressArgs) -> Result<()> {
    if args.bless {
        let reason = args.reason.as_deref().unwrap_or_default();
        if reason.trim().is_empty() {
            bail!("--bless needs a non-empty --reason");
        }
        for path in regress::bless(reason)? {
            say!("blessed {}", path.display());
        }
        return Ok(());
    }
    let outcomes = run_suite(args.long, &args.only)?;
    if outcomes.is_empty() {
        let named = regress::scenarios()
            .iter()
            .any(|s| s.name.contains(&args.only));
        if named && !args.long {
            bail!(
                "the scenarios matching '{}' run only with --long",
                args.only
            );
        }
        bail!("no scenario matches '{}'", args.only);
    }
    say!(
        "{:<40} {:>12} {:>12} {:>11}  result  unit",
        "scenario",
        "expected",
        "measured",
        "tolerance"
    );
    for o in &outcomes {
        say!("{o}");
    }
    if let Some(path) = &args.json {
        write_json(path, &json!({ "scenarios": outcomes, "long": args.long }))?;
    }
    let passed = outcomes.iter().filter(|o| o.pass).count();
    say!("{passed} of {} scenarios pass", outcomes.len());
    let failed = outcomes.len() - passed;
    if failed > 0 {
        bail!("{failed} scenario(s) failed");
    }
    Ok(())
}
