//! Runs the drape bench: `cargo run --release -p sim --example drape -- 64 4 10`.
fn main() {
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .map(|a| a.parse().unwrap())
        .collect();
    let mut bench = sim::drape_bench::DrapeBench::new(*args.first().unwrap_or(&64));
    if let Some(&s) = args.get(1) {
        bench.params.substeps = s;
    }
    if let Some(&i) = args.get(2) {
        bench.params.max_iterations = i;
    }
    let r = bench.run().unwrap();
    println!("{}", serde_json::to_string_pretty(&r).unwrap());
}
