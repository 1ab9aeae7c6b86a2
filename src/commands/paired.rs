//! `dit-garment paired`: two evaluations of the same recordings compared sequence by
//! sequence (`surrogate::evaluate::paired`).

use anyhow::Result;
use serde_json::json;
use surrogate::evaluate::paired::{compare, read, text_table};

use crate::cli::PairedArgs;
use files::write_json;

pub fn run(args: &PairedArgs) -> Result<()> {
    let a = read(&args.a, &args.method, &args.metric)?;
    let b = read(&args.b, &args.method, &args.metric)?;
    let rows = compare(&a, &b)?;
    if let Some(path) = &args.json {
        let document = json!({
            "a": args.a, "b": args.b, "method": args.method, "metric": args.metric,
            "rows": rows,
        });
        write_json(path, &document)?;
    }
    say!(
        "paired: {} of `{}`, B = {} minus A = {}, per sequence",
        args.metric,
        args.method,
        args.b.display(),
        args.a.display()
    );
    say_part!("{}", text_table(&rows));
    Ok(())
}
