//! What a cloth is besides its state ([`ClothSetup`]), checked against its mesh, and the
//! solver built from it: masses, constraints, the factorized global matrix per substep count
//! and the workspace.

use std::collections::BTreeMap;

use super::{LAGGED_BENDING_SHARE, Solver, Stage, StageTimes, Workspace};
use crate::cloth::{ClothMesh, Vec3};
use crate::constraints::{Attachment, BendingRest, Constraints, Seam, Spring};
use crate::error::{Error, Result};
use crate::params::{Material, SolverParams};
use crate::self_contact::SelfContactDetector;
use crate::system::GlobalSystem;

/// Everything that defines a cloth besides its state: mesh, material and constraints.
#[derive(Debug, Clone)]
pub struct ClothSetup {
    /// Mesh (its rest shape gives rest lengths and the curved bending rest state).
    pub mesh: ClothMesh,
    /// Material.
    pub material: Material,
    /// Bending rest state.
    pub bending_rest: BendingRest,
    /// Seams (zero-length springs) between vertex pairs.
    pub seams: Vec<Seam>,
    /// Extra springs with their own rest length and stiffness.
    pub springs: Vec<Spring>,
    /// Springs to moving targets (set with [`Solver::set_attachment_targets`]).
    pub attachments: Vec<Attachment>,
    /// Pinned vertices (velocity prescribed by their target positions).
    pub pins: Vec<u32>,
}

impl ClothSetup {
    /// A free cloth with a flat bending rest state.
    pub fn new(mesh: ClothMesh, material: Material) -> Self {
        Self {
            mesh,
            material,
            bending_rest: BendingRest::Flat,
            seams: Vec::new(),
            springs: Vec::new(),
            attachments: Vec::new(),
            pins: Vec::new(),
        }
    }

    /// Checks that every pin, seam, spring and attachment refers to vertices of the mesh and
    /// has a finite positive stiffness (and a finite non-negative rest length).
    pub fn check(&self) -> Result<()> {
        let n = self.mesh.num_vertices();
        let exists = |v: u32| (v as usize) < n;
        let stiff = |k: f64| k > 0.0 && k.is_finite();
        let fail = |kind, index, problem: String| {
            Err(Error::Constraint {
                kind,
                index,
                problem: format!("{problem} ({n} vertices)"),
            })
        };
        for (index, &p) in self.pins.iter().enumerate() {
            if !exists(p) {
                return fail("pin", index, format!("vertex {p} does not exist"));
            }
        }
        for (index, s) in self.seams.iter().enumerate() {
            if !exists(s.a) || !exists(s.b) || s.a == s.b || !stiff(s.stiffness) {
                return fail("seam", index, format!("{s:?}"));
            }
        }
        for (index, s) in self.springs.iter().enumerate() {
            let length = s.rest_length >= 0.0 && s.rest_length.is_finite();
            if !exists(s.a) || !exists(s.b) || s.a == s.b || !stiff(s.stiffness) || !length {
                return fail("spring", index, format!("{s:?}"));
            }
        }
        for (index, a) in self.attachments.iter().enumerate() {
            if !exists(a.vertex) || !stiff(a.stiffness) {
                return fail("attachment", index, format!("{a:?}"));
            }
        }
        Ok(())
    }
}

impl Solver {
    /// Checks the setup's constraints against the mesh and factorizes the global matrix for
    /// `params.substeps` steps per frame of `frame_dt` seconds. The material and the settings
    /// are the caller's to validate ([`Material::validate`], [`SolverParams::validate`]; a
    /// scene validates its configuration once, [`crate::config::SceneConfig::validate`]).
    pub fn new(setup: ClothSetup, params: SolverParams, frame_dt: f64) -> Result<Self> {
        debug_assert!(setup.material.validate().is_ok() && params.validate().is_ok());
        if !(frame_dt.is_finite() && frame_dt > 0.0) {
            return Err(Error::value(
                "frame time",
                frame_dt,
                "must be a positive number of seconds",
            ));
        }
        setup.check()?;
        let n = setup.mesh.num_vertices();
        let masses = setup.mesh.lumped_masses(setup.material.density);
        let constraints = Constraints::build(
            &setup.mesh,
            &setup.material,
            setup.bending_rest,
            &setup.seams,
            &setup.springs,
            &setup.attachments,
        );
        let (incidence_ptr, incidence) = constraints.incidence(n);
        let mut pinned = vec![false; n];
        for &p in &setup.pins {
            pinned[p as usize] = true;
        }
        let pin_targets = setup.mesh.rest().to_vec();
        let attachment_targets = setup
            .attachments
            .iter()
            .map(|a| setup.mesh.rest()[a.vertex as usize])
            .collect();
        let terms = constraints.len();
        let self_contact = params.self_contact.then(|| {
            let seams: Vec<[u32; 2]> = setup.seams.iter().map(|s| [s.a, s.b]).collect();
            SelfContactDetector::new(n, setup.mesh.triangles(), setup.mesh.edges(), &seams)
        });
        let mut solver = Self {
            params,
            frame_dt,
            masses,
            constraints,
            incidence_ptr,
            incidence,
            pinned,
            pin_targets,
            attachment_targets,
            seam_length_cap: f64::INFINITY,
            systems: BTreeMap::new(),
            symbolic: [None, None],
            self_contact,
            ws: Workspace {
                v_star: vec![Vec3::zeros(); n],
                predicted: vec![Vec3::zeros(); n],
                positions: vec![Vec3::zeros(); n],
                ax_start: vec![Vec3::zeros(); terms],
                q: vec![Vec3::zeros(); terms],
                rhs: vec![Vec3::zeros(); n],
                v: vec![Vec3::zeros(); n],
                v_next: vec![Vec3::zeros(); n],
                contacts: Vec::new(),
                impulses: Vec::new(),
                effective_mass: Vec::new(),
                in_contact: vec![false; n],
                self_contacts: Vec::new(),
                self_impulses: Vec::new(),
                self_mass: Vec::new(),
                self_nodes: Vec::new(),
                node_mass: vec![0.0; n],
                node_free: vec![Vec3::zeros(); n],
                patch_load: vec![0.0; n],
                patch_response: vec![0.0; n],
            },
            times: StageTimes::default(),
            anderson: (params.acceleration > 0)
                .then(|| super::anderson::Anderson::new(params.acceleration)),
            setup,
        };
        solver.system_for(params.substeps)?;
        Ok(solver)
    }

    /// Factorizes the global matrix for `substeps` steps per frame, once per count.
    pub(super) fn system_for(&mut self, substeps: usize) -> Result<()> {
        if self.systems.contains_key(&substeps) {
            return Ok(());
        }
        self.timed(Stage::Factorize, |s| s.factorize(substeps))
    }

    fn factorize(&mut self, substeps: usize) -> Result<()> {
        let h = self.frame_dt / substeps as f64;
        let share = self.constraints.bending_share(&self.masses, h);
        let lag = share < LAGGED_BENDING_SHARE;
        let system = GlobalSystem::new(
            &self.masses,
            &self.constraints,
            h,
            &self.pinned,
            lag,
            self.symbolic[lag as usize].clone(),
        )?;
        self.symbolic[lag as usize] = Some(system.symbolic());
        self.systems.insert(substeps, system);
        Ok(())
    }
}
