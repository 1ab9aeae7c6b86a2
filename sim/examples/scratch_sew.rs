fn main() {
    let model = motions::BodyModel::default_body();
    let names: Vec<String> = std::env::args().skip(1).collect();
    for name in names {
        let path = format!("../shared/testdata/garmentcode/{name}_specification.json");
        let t = std::time::Instant::now();
        let p = garments::Pattern::read(std::path::Path::new(&path)).unwrap();
        let m = p.mesh(0.015).unwrap();
        let (g, r) = sim::sewing::sew(&model, &m, &sim::sewing::SewingOptions::default()).unwrap();
        println!("{name}: {:?} total {:?}", r, t.elapsed());
        let f = std::fs::File::create(format!("/tmp/{name}_draped.obj")).unwrap();
        garments::write_obj(&mut std::io::BufWriter::new(f), &g, None).unwrap();
    }
}
