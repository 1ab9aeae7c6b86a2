//! The learned surrogate, DiT-Garment (not yet implemented; see the surrogate issues).
//!
//! This crate will hold UV geometry images (rasterize and read back), the 2D diffusion
//! transformer with linear attention over 64x64 UV maps, rectified-flow training, iterative
//! sampling with intersection guidance, and safetensors checkpoints.
