//! Geometry images and the frames they live in: the atlas of a template (`atlas.rs`), encode
//! and readback (`maps.rs`), the canonical frame (`canonical.rs`), the template skinned to a
//! body (`skinning.rs`), the two targets (`target.rs`), the nearest body point of each
//! vertex (`nearest.rs`) and the panels new UVs are cut in (`panels.rs`).

mod atlas;
mod canonical;
mod maps;
mod nearest;
mod panels;
mod skinning;
mod target;

pub use atlas::{Atlas, RESOLUTIONS, TexelSample};
pub use canonical::{Canonical, RootRemoval};
pub use maps::GeometryImage;
pub use nearest::{PosedSurface, nearest_body};
pub use panels::panel_guide;
pub use skinning::{FOLDED_JOINTS, SMOOTHING_ROUNDS, Skinning};
pub use target::{FrameBase, FrameBody, TargetKind, Targets};
