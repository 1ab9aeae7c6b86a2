//! `dit-garment regress`: the physics regression suite as a table and JSON; exits non-zero if
//! a scenario fails (known-open ones are marked and do not fail the run).

use anyhow::{Result, bail};
use serde_json::json;
use sim::regress::{KNOWN_OPEN, run as run_suite};

use crate::cli::RegressArgs;
use crate::output::write_json;

pub fn run(args: &RegressArgs) -> Result<()> {
    if args.bless {
        let reason = args.reason.as_deref().unwrap_or_default();
        if reason.trim().is_empty() {
            bail!("--bless needs a non-empty --reason");
        }
        for path in sim::regress::bless(reason)? {
            println!("blessed {}", path.display());
        }
        return Ok(());
    }
    let outcomes = run_suite(args.long, &args.only)?;
    if outcomes.is_empty() {
        bail!("no scenario matches '{}'", args.only);
    }
    println!(
        "{:<40} {:>12} {:>12} {:>11}  result  unit",
        "scenario", "expected", "measured", "tolerance"
    );
    let mut failed = 0;
    for o in &outcomes {
        let known = KNOWN_OPEN.contains(&o.name.as_str());
        let result = match (o.pass, known) {
            (true, _) => "pass",
            (false, true) => "open",
            (false, false) => "FAIL",
        };
        failed += (!o.pass && !known) as usize;
        println!(
            "{:<40} {:>12.6} {:>12.6} {:>11.3e}  {result:<6}  {}",
            o.name, o.expected, o.measured, o.tolerance, o.unit
        );
    }
    if let Some(path) = &args.json {
        write_json(
            path,
            &json!({ "scenarios": outcomes, "known_open": KNOWN_OPEN, "long": args.long }),
        )?;
    }
    let passed = outcomes.iter().filter(|o| o.pass).count();
    println!("{passed} of {} scenarios pass", outcomes.len());
    if failed > 0 {
        bail!("{failed} scenario(s) failed");
    }
    Ok(())
}
