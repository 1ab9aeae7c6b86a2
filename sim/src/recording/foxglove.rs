//! The optional `foxglove.SceneUpdate` channel: garment and body as triangle lists every
//! frame, z up, so Foxglove's 3D panel plays a recording without our code.

/// Foxglove's `foxglove.SceneUpdate` message, the parts this project writes (triangle lists);
/// Foxglove recognizes the schema by its name.
pub(super) const FOXGLOVE_SCENE_SCHEMA: &str = r#"{
  "title": "foxglove.SceneUpdate",
  "description": "An update to the entities displayed in a 3D scene",
  "type": "object",
  "properties": {
    "deletions": {"type": "array", "items": {"type": "object"}},
    "entities": {"type": "array", "items": {"type": "object", "properties": {
      "timestamp": {"type": "object", "properties": {"sec": {"type": "integer"}, "nsec": {"type": "integer"}}},
      "frame_id": {"type": "string"},
      "id": {"type": "string"},
      "lifetime": {"type": "object", "properties": {"sec": {"type": "integer"}, "nsec": {"type": "integer"}}},
      "frame_locked": {"type": "boolean"},
      "metadata": {"type": "array"},
      "arrows": {"type": "array"}, "cubes": {"type": "array"}, "spheres": {"type": "array"},
      "cylinders": {"type": "array"}, "lines": {"type": "array"}, "texts": {"type": "array"},
      "models": {"type": "array"},
      "triangles": {"type": "array", "items": {"type": "object", "properties": {
        "pose": {"type": "object"},
        "points": {"type": "array", "items": {"type": "object", "properties": {"x": {"type": "number"}, "y": {"type": "number"}, "z": {"type": "number"}}}},
        "color": {"type": "object", "properties": {"r": {"type": "number"}, "g": {"type": "number"}, "b": {"type": "number"}, "a": {"type": "number"}}},
        "colors": {"type": "array"},
        "indices": {"type": "array", "items": {"type": "integer", "minimum": 0}}
      }}}
    }}}
  }
}"#;
/// The Foxglove scene channel and the triangles its messages repeat.
pub(super) struct FoxgloveScene {
    pub channel: u16,
    pub garment_triangles: Vec<[u32; 3]>,
    pub body_faces: Vec<[u32; 3]>,
}

/// One `foxglove.TriangleListPrimitive` entity: y-up points turned z-up by the pose (+90
/// degrees about x), rounded to 0.1 mm to keep the JSON short.
pub(super) fn foxglove_entity(
    id: &str,
    time_ns: u64,
    points: impl Iterator<Item = [f64; 3]>,
    triangles: &[[u32; 3]],
    rgb: [f64; 3],
) -> serde_json::Value {
    let round = |v: f64| (v * 1e4).round() / 1e4;
    let points: Vec<serde_json::Value> = points
        .map(|p| serde_json::json!({"x": round(p[0]), "y": round(p[1]), "z": round(p[2])}))
        .collect();
    let half = std::f64::consts::FRAC_1_SQRT_2;
    serde_json::json!({
        "timestamp": {"sec": time_ns / 1_000_000_000, "nsec": time_ns % 1_000_000_000},
        "frame_id": "world", "id": id,
        "lifetime": {"sec": 0, "nsec": 0}, "frame_locked": false, "metadata": [],
        "arrows": [], "cubes": [], "spheres": [], "cylinders": [], "lines": [], "texts": [],
        "models": [],
        "triangles": [{
            "pose": {"position": {"x": 0.0, "y": 0.0, "z": 0.0},
                     "orientation": {"x": half, "y": 0.0, "z": 0.0, "w": half}},
            "points": points,
            "color": {"r": rgb[0], "g": rgb[1], "b": rgb[2], "a": 1.0},
            "colors": [],
            "indices": triangles.iter().flatten().collect::<Vec<_>>(),
        }],
    })
}
