//! A BVH file of any bytes: parsed, matched to a built-in joint map, retargeted onto the
//! default body, or refused.
#![no_main]

use std::path::Path;
use std::sync::OnceLock;

use libfuzzer_sys::fuzz_target;
use motions::bvh::{Bvh, JointMap, retarget};
use motions::{BodyModel, ShapedBody};

/// The default body, shaped once: loading it per input would leave little time for fuzzing.
fn shaped() -> &'static ShapedBody {
    static SHAPED: OnceLock<ShapedBody> = OnceLock::new();
    SHAPED.get_or_init(|| {
        let model = BodyModel::default_body();
        model.shape(&[]).expect("the default body shapes")
    })
}

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(bvh) = Bvh::parse(text, Path::new("fuzz.bvh")) else {
        return;
    };
    let _ = bvh.pose(0);
    if let Ok(map) = JointMap::builtin_for(&bvh)
        && let Ok(r) = retarget(&bvh, &map, shaped())
    {
        let _ = r.motion.resample(30.0);
    }
});
