//! The previous-state input of an autoregressive model (`model.previous_state`): the
//! garment's normalized target map at the frame before, inside the loss mask. Training feeds
//! the simulated one (noised, `train/batch.rs`), prediction the model's own output; a frame
//! with no frame before it gets the map of a zero target (for `lbs_residual`, the template as
//! skinned), the same in both.

use super::Stats;

/// The input map `[3, plane]` for a frame whose previous normalized target map is `previous`
/// (`[3, plane]`), or none; `mask` is the template's loss mask `[plane]`.
pub fn previous_state_map(previous: Option<&[f32]>, mask: &[f32], targets: &Stats) -> Vec<f32> {
    let plane = mask.len();
    match previous {
        Some(map) => map
            .iter()
            .enumerate()
            .map(|(k, &v)| v * mask[k % plane])
            .collect(),
        None => {
            let mut zero = vec![0.0f32; 3 * plane];
            targets.normalize(&mut zero, plane);
            zero.iter()
                .enumerate()
                .map(|(k, &v)| v * mask[k % plane])
                .collect()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_map_keeps_the_mask_and_a_missing_frame_is_a_zero_target() {
        let stats = Stats {
            mean: vec![1.0, -2.0, 0.5],
            std: vec![2.0, 0.5, 1.0],
        };
        let mask = [1.0, 0.0];
        let previous = [3.0f32, 4.0, 5.0, 6.0, 7.0, 8.0];
        assert_eq!(
            previous_state_map(Some(&previous), &mask, &stats),
            [3.0, 0.0, 5.0, 0.0, 7.0, 0.0]
        );
        // (0 - mean) / std inside the mask.
        assert_eq!(
            previous_state_map(None, &mask, &stats),
            [-0.5, 0.0, 4.0, 0.0, -0.5, 0.0]
        );
    }
}
