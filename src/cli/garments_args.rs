//! The `garments` subcommands' flags (plain values, no I/O).

use std::path::PathBuf;

use clap::Subcommand;

use super::ModelArgs;

/// What `garments` does: list, show, make, import or check a garment.
#[derive(Debug, Subcommand)]
pub enum GarmentsCommand {
    /// List the library's designs: name, split, vertices at the default resolution, what it is.
    List {
        /// Also write the list as a JSON array (`name`, `split`, `vertices`, ...).
        #[arg(long)]
        json: Option<PathBuf>,
    },
    /// Describe one design: parameters, panels, stitches, mesh size.
    Show {
        /// Design name (see `garments list`).
        name: String,
        /// Write its sewing pattern (GarmentCode specification JSON) here.
        #[arg(long)]
        pattern_out: Option<PathBuf>,
    },
    /// Sew and drape a design or a GarmentCode pattern into a template on the default body.
    /// Exits non-zero when a quality gate fails (the template and report are still written).
    Make {
        /// Design name or `*_specification.json` file.
        source: String,
        /// Template output: .obj (with UVs and panel groups) or .ply.
        #[arg(long)]
        out: PathBuf,
        /// Write the gates, counts and timings to this JSON file.
        #[arg(long)]
        report: Option<PathBuf>,
        /// Target triangle edge length, m.
        #[arg(long, default_value_t = garments::pattern::DEFAULT_EDGE_LENGTH_M)]
        edge_length: f64,
    },
    /// Make a garment mesh worn by a posed, shaped body (a scan, an artist's garment, a frame
    /// of a capture: OBJ or PLY, UVs optional) a template on the default body: cleaned,
    /// subdivided where coarse, carried back to the canonical pose and shape by the engine and
    /// settled there with the gates of `make`, and given UVs where it has none or its charts
    /// overlap. Exits non-zero when a gate fails (the template and report are still written).
    Import {
        /// The garment mesh (.obj or .ply), in metres unless `--scale` says otherwise.
        mesh: PathBuf,
        /// The motion of the body wearing it: a built-in name, an AMASS-style .npz or a BVH
        /// file (as `simulate --motion` takes it).
        #[arg(long)]
        motion: String,
        /// The motion's frame the mesh is worn at (0-based, at 30 fps; a `simulate` recording's
        /// frame K is the motion's frame K minus the blend and settle frames).
        #[arg(long)]
        frame: usize,
        /// The body's shape coefficients, comma-separated (default: the motion file's own, else
        /// zeros).
        #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
        betas: Option<Vec<f64>>,
        /// Template output: .obj (with UVs) or .ply.
        #[arg(long)]
        out: PathBuf,
        /// Scale the mesh's positions by this factor first (0.01 for a mesh in cm).
        #[arg(long, default_value_t = 1.0)]
        scale: f64,
        /// The rest shape's size against the worn mesh, 0.8 to 1: below 1 for cloth worn
        /// stretched by its weight and its body (the default, measured on worn garments:
        /// docs/GARMENTS.md), 1 for a mesh that is not stretched (a garment lying flat).
        #[arg(long, default_value_t = surrogate::import::REST_SHRINK)]
        rest_shrink: f64,
        /// Write what each stage did and the drape's gates to this JSON file.
        #[arg(long)]
        report: Option<PathBuf>,
        #[command(flatten)]
        model: ModelArgs,
    },
    /// Check a garment mesh (OBJ) or sewing pattern (JSON) and print what is wrong and what
    /// would be repaired; exits non-zero when it cannot be used.
    Check {
        /// OBJ mesh or GarmentCode specification JSON.
        file: PathBuf,
        /// Scale positions by this factor first (0.01 for a mesh in cm).
        #[arg(long, default_value_t = 1.0)]
        scale: f64,
        /// Also write the findings to this JSON file.
        #[arg(long)]
        json: Option<PathBuf>,
    },
}
