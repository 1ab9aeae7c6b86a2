fn main() {
    let model = motions::BodyModel::default_body();
    let names: Vec<String> = std::env::args().skip(1).collect();
    for name in names {
        let t = std::time::Instant::now();
        let p = match garments::library::find(&name) {
            Some(d) => d.pattern().unwrap(),
            None => garments::Pattern::read(std::path::Path::new(&format!("../shared/testdata/garmentcode/{name}_specification.json"))).unwrap(),
        };
        let m = p.mesh(0.015).unwrap();
        match sim::sewing::sew(&model, &m, &sim::sewing::SewingOptions::default()) {
            Ok((g, r)) => {
                println!("{name}: pass {} v {} inside {} gap {:.2}mm moving {:.3} stretch {:.3} frames {}+{} {:.1}s {:?}", r.gates_passed, r.vertices, r.verts_inside, r.max_seam_gap_m*1e3, r.moving_fraction, r.max_edge_stretch, r.close_frames, r.settle_frames, t.elapsed().as_secs_f64(), r.failed);
                let f = std::fs::File::create(format!("/tmp/dbg/{name}.obj")).unwrap();
                garments::write_obj(&mut std::io::BufWriter::new(f), &g, None).unwrap();
            }
            Err(e) => println!("{name}: ERROR {e}"),
        }
    }
}
