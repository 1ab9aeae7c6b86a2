//! Measures the body point queries the engine needs through rapier3d's collider set and query
//! pipeline against direct parry3d queries (what the engine uses), on the default body and the
//! built-in skirt's vertices:
//! `cargo run --release -p sim --features rapier --example rapier_queries`.

use std::time::Instant;

use motions::BodyModel;
use parry3d::math::Vector;
use parry3d::query::{DefaultQueryDispatcher, PointQuery, PointQueryWithLocation};
use parry3d::shape::{TriMesh, TriMeshFlags};
use rapier3d::prelude::{
    BroadPhaseBvh, ColliderBuilder, ColliderSet, IntegrationParameters, QueryFilter, RigidBodySet,
};

fn main() {
    let model = BodyModel::default_body();
    let body = sim::scene::canonical_body(&model).unwrap();
    let vertices: Vec<Vector> = body
        .vertices
        .iter()
        .map(|p| Vector::new(p[0] as f32, p[1] as f32, p[2] as f32))
        .collect();
    let skirt =
        garments::skirt("default", &body.vertices, &garments::SkirtParams::default()).unwrap();
    let points: Vec<Vector> = skirt
        .positions
        .iter()
        .map(|p| Vector::new(p[0] as f32, p[1] as f32 - 0.01, p[2] as f32))
        .collect();
    let flags = TriMeshFlags::ORIENTED | TriMeshFlags::DEFORMABLE;
    let rounds = 20;

    // Direct parry3d: refit in place, then closest point with triangle and barycentrics.
    let mut mesh = TriMesh::with_flags(vertices.clone(), model.faces().to_vec(), flags).unwrap();
    let started = Instant::now();
    for _ in 0..rounds {
        mesh.set_vertices(&vertices);
    }
    let parry_update = started.elapsed().as_secs_f64() / rounds as f64;
    let started = Instant::now();
    let mut parry_inside = 0;
    for _ in 0..rounds {
        parry_inside = points
            .iter()
            .filter(|p| {
                mesh.project_local_point_and_get_location_with_max_dist(**p, false, 0.03)
                    .is_some_and(|(proj, _)| proj.is_inside)
            })
            .count();
    }
    let parry_query = started.elapsed().as_secs_f64() / rounds as f64;

    // rapier3d: a trimesh collider in a collider set, its AABB in the broad-phase BVH, queries
    // through the query pipeline. Updating a deforming mesh means replacing the shape.
    let mut colliders = ColliderSet::new();
    let bodies = RigidBodySet::new();
    let handle = colliders.insert(
        ColliderBuilder::trimesh_with_flags(vertices.clone(), model.faces().to_vec(), flags)
            .unwrap()
            .build(),
    );
    let mut broad_phase = BroadPhaseBvh::new();
    let params = IntegrationParameters::default();
    let started = Instant::now();
    for _ in 0..rounds {
        let shape = rapier3d::prelude::SharedShape::trimesh_with_flags(
            vertices.clone(),
            model.faces().to_vec(),
            flags,
        )
        .unwrap();
        colliders[handle].set_shape(shape);
        broad_phase.set_aabb(&params, handle, colliders[handle].compute_aabb());
    }
    let rapier_update = started.elapsed().as_secs_f64() / rounds as f64;
    let dispatcher = DefaultQueryDispatcher;
    let pipeline =
        broad_phase.as_query_pipeline(&dispatcher, &bodies, &colliders, QueryFilter::default());
    let started = Instant::now();
    let mut rapier_inside = 0;
    for _ in 0..rounds {
        rapier_inside = points
            .iter()
            .filter(|p| {
                pipeline
                    .project_point(**p, 0.03, false)
                    .is_some_and(|(_, proj)| proj.is_inside)
            })
            .count();
    }
    let rapier_query = started.elapsed().as_secs_f64() / rounds as f64;
    // Sanity: the same answers.
    let _ = mesh.project_local_point(points[0], false);
    println!(
        "{} body triangles, {} query points (one core)",
        model.faces().len(),
        points.len()
    );
    println!(
        "parry3d direct : update {:.2} ms (refit in place), queries {:.2} ms, {} inside, triangle + barycentrics available",
        parry_update * 1e3,
        parry_query * 1e3,
        parry_inside
    );
    println!(
        "rapier3d pipeline: update {:.2} ms (shape rebuilt), queries {:.2} ms, {} inside, no barycentrics (project_point / _and_get_feature only)",
        rapier_update * 1e3,
        rapier_query * 1e3,
        rapier_inside
    );
}
