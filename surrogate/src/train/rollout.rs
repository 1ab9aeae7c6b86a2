//! Training on the network's own rollouts (`training.rollout`, the autoregressive mode).
//!
//! Teacher forcing shows a previous-state network the simulated frame before, with noise that
//! stands in for its errors; at prediction it is given its own output, whose errors are neither
//! that small nor that shapeless, and they compound (arms a19 and a20, docs/SURROGATE_ARMS.md). Here,
//! before a step, the network as it is at that step is run without gradients over up to
//! `rollout` frames before each sample, each frame given the output for the one before (the
//! first given the simulated frame with noise, or the zero-target map at a sequence's start),
//! and the sample gets the last output as its previous state. The gradient flows through the
//! sample's own frame only: the pushforward trick of Brandstetter, Worrall and Welling,
//! "Message Passing Neural PDE Solvers" (ICLR 2022). The unrolled depth is drawn per step from
//! 0 to `rollout` from its own stream, so a resumed run unrolls as the uninterrupted one did.

use burn::prelude::*;
use rand::Rng;

use super::TrainingData;
use super::batch::Batch;
use crate::data::Frames;
use crate::model::Dit;
use crate::noise::generator;
use crate::run::TrainConfig;

/// Stream of the unrolled depths and of the unrolled frames' noise.
pub const ROLLOUT_STREAM: u64 = 3;

/// Up to `depth` frames before frame `f` of `split`, oldest first (fewer near a sequence's
/// start).
fn frames_before(split: &Frames, f: usize, depth: usize) -> Vec<usize> {
    let mut chain = Vec::with_capacity(depth);
    let mut at = f;
    while chain.len() < depth {
        match split.previous(at) {
            Some(p) => {
                chain.push(p);
                at = p;
            }
            None => break,
        }
    }
    chain.reverse();
    chain
}

/// The previous-state maps the training batch of `step` over `frames` (of the train split) is
/// given: the network's own output for the frame before each (`model` without gradients, on
/// `device`), after unrolling a depth drawn from 0 to `training.rollout`; `None` where the
/// depth is 0 or the frame starts its sequence (it keeps the simulated previous frame).
pub(super) fn own_previous(
    model: &Dit,
    data: &TrainingData,
    frames: &[usize],
    training: &TrainConfig,
    step: usize,
    device: &Device,
) -> Vec<Option<Vec<f32>>> {
    let split = &data.train;
    let mut rng = generator(training.seed, ROLLOUT_STREAM, step as u64);
    let depth = rng.random_range(0..=training.rollout);
    let chains: Vec<Vec<usize>> = frames
        .iter()
        .map(|&f| frames_before(split, f, depth))
        .collect();
    let mut own: Vec<Option<Vec<f32>>> = vec![None; frames.len()];
    // Chains end together, at the frame before their sample: a shorter chain joins later.
    for j in 0..depth {
        let active: Vec<(usize, usize)> = chains
            .iter()
            .enumerate()
            .filter(|(_, c)| j + c.len() >= depth)
            .map(|(i, c)| (i, c[j + c.len() - depth]))
            .collect();
        if active.is_empty() {
            continue;
        }
        let unrolled: Vec<usize> = active.iter().map(|&(_, g)| g).collect();
        let given: Vec<Option<Vec<f32>>> = active.iter().map(|&(i, _)| own[i].take()).collect();
        let times = vec![1.0; unrolled.len()];
        let batch = Batch::with_own_previous(
            &data.tensors,
            split,
            &unrolled,
            &times,
            data.recipe,
            &mut rng,
            &given,
        );
        let (noisy, position, mask, time, conditions) = batch.inputs(device);
        let out = model.forward(noisy, position, mask, time, conditions);
        let values: Vec<f32> = out
            .into_data()
            .try_into_vec::<f32>()
            .expect("the network computes in f32");
        let per_frame = values.len() / unrolled.len();
        for (&(i, _), map) in active.iter().zip(values.chunks(per_frame)) {
            own[i] = Some(map.to_vec());
        }
    }
    own
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frames(sequence: &[usize], frame: &[usize]) -> Frames {
        Frames {
            template: vec![0; sequence.len()],
            sequence: sequence.to_vec(),
            frame: frame.to_vec(),
            ..Frames::default()
        }
    }

    #[test]
    fn a_chain_holds_the_frames_before_and_stops_at_its_sequence_start() {
        let split = frames(&[0, 0, 0, 0, 1, 1], &[0, 1, 2, 3, 0, 1]);
        assert_eq!(frames_before(&split, 3, 2), vec![1, 2]);
        assert_eq!(frames_before(&split, 3, 9), vec![0, 1, 2]);
        assert_eq!(frames_before(&split, 5, 3), vec![4]);
        assert_eq!(frames_before(&split, 4, 3), Vec::<usize>::new());
        assert_eq!(frames_before(&split, 2, 0), Vec::<usize>::new());
    }
}
