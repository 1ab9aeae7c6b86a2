//! A BVH file of any bytes: parsed, matched to a built-in joint map, retargeted onto the
//! default body, or refused.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use motions::BodyModel;
use motions::bvh::{Bvh, JointMap, retarget};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(bvh) = Bvh::parse(text, Path::new("fuzz.bvh")) else {
        return;
    };
    let _ = bvh.pose(0);
    if let Ok(map) = JointMap::builtin_for(&bvh) {
        let model = BodyModel::default_body();
        let shaped = model.shape(&[]).expect("the default body shapes");
        if let Ok(r) = retarget(&bvh, &map, &shaped) {
            let _ = r.motion.resample(30.0);
        }
    }
});
