//! Which part of a dataset a sequence belongs to, and whether it passed its gates: the two
//! enums every manifest line carries (as the strings `train`, `test_grid`, `ok`, ...).

use serde::{Deserialize, Serialize};

/// A dataset split: training, or one of the held-out sets (what each holds out is in
/// docs/DATASETS.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Split {
    /// Training sequences.
    Train,
    /// Unseen garment, motion, shape and material.
    Test,
    /// Only the garment unseen.
    TestGarment,
    /// Only the motion unseen.
    TestMotion,
    /// Only the shape unseen.
    TestShape,
    /// Only the material unseen.
    TestMaterial,
    /// Every held-out garment x every held-out motion x its shapes (a full grid).
    TestGrid,
}

impl Split {
    /// Every split, in manifest order.
    pub const ALL: [Split; 7] = [
        Split::Train,
        Split::Test,
        Split::TestGarment,
        Split::TestMotion,
        Split::TestShape,
        Split::TestMaterial,
        Split::TestGrid,
    ];

    /// The split's name in manifests, flags and file names.
    pub fn name(self) -> &'static str {
        match self {
            Split::Train => "train",
            Split::Test => "test",
            Split::TestGarment => "test_garment",
            Split::TestMotion => "test_motion",
            Split::TestShape => "test_shape",
            Split::TestMaterial => "test_material",
            Split::TestGrid => "test_grid",
        }
    }

    /// The split called `name`, if any.
    pub fn parse(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|s| s.name() == name)
    }

    /// Every split's name, comma-separated (for error messages).
    pub fn names() -> String {
        Self::ALL.map(Split::name).join(", ")
    }
}

impl std::fmt::Display for Split {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Whether a sequence passed every gate (`ok`, kept for training) or not (`failed`, kept for
/// inspection with its reason).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Status {
    /// Every gate passed.
    Ok,
    /// Some gate failed, or no attempt finished.
    Failed,
}

impl std::fmt::Display for Status {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str(match self {
            Status::Ok => "ok",
            Status::Failed => "failed",
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_through_serde_and_parse() {
        for s in Split::ALL {
            let json = serde_json::to_string(&s).unwrap();
            assert_eq!(json, format!("\"{}\"", s.name()));
            assert_eq!(serde_json::from_str::<Split>(&json).unwrap(), s);
            assert_eq!(Split::parse(s.name()), Some(s));
        }
        assert_eq!(Split::parse("training"), None);
        assert_eq!(
            serde_json::to_string(&Status::Failed).unwrap(),
            "\"failed\""
        );
        assert!(serde_json::from_str::<Status>("\"passed\"").is_err());
    }
}
