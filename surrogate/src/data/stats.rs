//! Normalization statistics: mean and standard deviation per channel, with the normalization
//! training and prediction both apply and its inverse.

use serde::{Deserialize, Serialize};

/// Mean and standard deviation per channel.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Stats {
    /// Means.
    pub mean: Vec<f64>,
    /// Standard deviations (1 where a channel is constant).
    pub std: Vec<f64>,
}

impl Stats {
    /// `(x - mean_c) / std_c` in place over `[.., C, plane]` blocks (channel c = block index
    /// mod C): what training and prediction both feed the network.
    pub fn normalize(&self, values: &mut [f32], plane: usize) {
        let channels = self.mean.len();
        for (k, chunk) in values.chunks_mut(plane).enumerate() {
            let c = k % channels;
            let (m, s) = (self.mean[c] as f32, self.std[c] as f32);
            chunk.iter_mut().for_each(|v| *v = (*v - m) / s);
        }
    }

    /// Channels-first `[C, plane]` values back in the data's units, channels last (one
    /// `[f64; C]` per texel): `x std_c + mean_c`.
    pub fn denormalize<const C: usize>(&self, values: &[f32]) -> Vec<[f64; C]> {
        let plane = values.len() / C;
        (0..plane)
            .map(|k| {
                std::array::from_fn(|c| values[c * plane + k] as f64 * self.std[c] + self.mean[c])
            })
            .collect()
    }
}

/// Mean and standard deviation of `count` samples accumulated as sums.
pub(crate) fn stats(sum: &[f64], sum2: &[f64], count: f64) -> Stats {
    let mean: Vec<f64> = sum.iter().map(|s| s / count.max(1.0)).collect();
    let std = sum2
        .iter()
        .zip(&mean)
        .map(|(s2, m)| {
            let var = (s2 / count.max(1.0) - m * m).max(0.0);
            if var > 1e-24 { var.sqrt() } else { 1.0 }
        })
        .collect();
    Stats { mean, std }
}

#[cfg(test)]
mod tests {
    use super::Stats;

    #[test]
    fn channels_normalize_per_block_and_come_back_as_texels() {
        let stats = Stats {
            mean: vec![1.0, -2.0, 0.5],
            std: vec![2.0, 0.5, 1.0],
        };
        // Two texels, channels first: x = [1, 3], y = [-2, -1], z = [0.5, 1.5].
        let data = [1.0f32, 3.0, -2.0, -1.0, 0.5, 1.5];
        let mut values = data;
        stats.normalize(&mut values, 2);
        assert_eq!(values, [0.0, 1.0, 0.0, 2.0, 0.0, 1.0]);
        let texels = stats.denormalize::<3>(&values);
        assert_eq!(texels, [[1.0, -2.0, 0.5], [3.0, -1.0, 1.5]]);
        // A plane of 1 (a condition vector): every value is its own channel, cyclically.
        let mut vector = [3.0f32, -1.0, 1.5];
        stats.normalize(&mut vector, 1);
        assert_eq!(vector, [1.0, 2.0, 1.0]);
    }
}
