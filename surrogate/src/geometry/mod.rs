//! Geometry images and the frames they live in: the atlas of a template (`atlas.rs`), encode
//! and readback (`maps.rs`), the canonical frame (`canonical.rs`), the template skinned to a
//! body (`skinning.rs`), the two targets (`target.rs`) and the nearest body point of each
//! vertex (`nearest.rs`).

mod atlas;
mod canonical;
mod maps;
mod nearest;
mod skinning;
mod target;

pub use atlas::{Atlas, RESOLUTIONS, TexelSample};
pub use canonical::{Canonical, RootRemoval};
pub use maps::GeometryImage;
pub use nearest::{PosedSurface, nearest_body};
pub use skinning::{FOLDED_JOINTS, SMOOTHING_ROUNDS, Skinning, unpose};
pub use target::{FrameBase, FrameBody, TargetKind, Targets};
