//! A NumPy archive of any bytes: every array read, then taken as an AMASS motion and as a
//! body model, or refused.
#![no_main]

use std::io::Cursor;
use std::path::Path;

use libfuzzer_sys::fuzz_target;
use motions::npz::Npz;

fuzz_target!(|data: &[u8]| {
    let path = Path::new("fuzz.npz");
    if let Ok(mut npz) = Npz::from_reader(Cursor::new(data), path) {
        for key in npz.keys() {
            let _ = npz.numeric(&key);
            let _ = npz.strings(&key);
        }
    }
    if let Ok(npz) = Npz::from_reader(Cursor::new(data), path) {
        if let Ok(motion) = motions::amass::from_npz(npz, [0.0, -0.2, 0.0]) {
            let _ = motion.resample(30.0);
        }
    }
    let _ = motions::BodyModel::from_npz_bytes(data, path);
});
