//! Which part of a dataset one process synthesizes: shard K of N takes every N-th planned
//! sequence from the K-th. The shard comes from `--shard K/N`, else a Slurm job array
//! (`SLURM_ARRAY_TASK_ID`, `_COUNT`, `_MIN`), else a Kubernetes indexed job
//! (`JOB_COMPLETION_INDEX` with the job's completions), else the whole dataset.

use crate::error::{Error, Result};

/// Shard `index` of `count`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// K, from 0.
    pub index: usize,
    /// N.
    pub count: usize,
}

impl Shard {
    /// The whole dataset.
    pub const WHOLE: Shard = Shard { index: 0, count: 1 };

    /// The shard asked for: `flag` (`K/N`), else the job-array variables `env` returns (the
    /// process environment in use; a test passes its own), with `completions` the Kubernetes
    /// job's, else [`Shard::WHOLE`].
    pub fn resolve(
        flag: Option<&str>,
        completions: Option<usize>,
        env: impl Fn(&str) -> Option<String>,
    ) -> Result<Self> {
        let bad = Error::Shard;
        let number = |name: &str| -> Result<Option<usize>> {
            env(name)
                .map(|v| {
                    v.trim().parse().map_err(|_| {
                        bad(format!("environment variable {name}='{v}' is not a number"))
                    })
                })
                .transpose()
        };
        let (index, count) = if let Some(s) = flag {
            let whole = |v: &str| v.trim().parse::<usize>().ok();
            match s.split_once('/').map(|(k, n)| (whole(k), whole(n))) {
                Some((Some(k), Some(n))) => (k, n),
                _ => {
                    return Err(bad(format!(
                        "--shard '{s}' must be K/N with whole numbers, e.g. 0/4"
                    )));
                }
            }
        } else if let Some(id) = number("SLURM_ARRAY_TASK_ID")? {
            let count = number("SLURM_ARRAY_TASK_COUNT")?.ok_or_else(|| {
                bad("SLURM_ARRAY_TASK_ID is set but SLURM_ARRAY_TASK_COUNT is not".into())
            })?;
            let min = number("SLURM_ARRAY_TASK_MIN")?.unwrap_or(0);
            let index = id
                .checked_sub(min)
                .ok_or_else(|| bad("SLURM_ARRAY_TASK_ID < SLURM_ARRAY_TASK_MIN".into()))?;
            (index, count)
        } else if let Some(index) = number("JOB_COMPLETION_INDEX")? {
            let count = completions.ok_or_else(|| {
                bad(
                    "JOB_COMPLETION_INDEX is set: pass the job's completions as --shard-count"
                        .into(),
                )
            })?;
            (index, count)
        } else {
            return Ok(Self::WHOLE);
        };
        if count == 0 || index >= count {
            return Err(bad(format!(
                "shard {index}/{count} is out of range (K must be below N)"
            )));
        }
        Ok(Self { index, count })
    }

    /// The shard's part of `planned`, in order.
    pub fn take<'a, T>(&self, planned: &'a [T]) -> Vec<&'a T> {
        planned
            .iter()
            .skip(self.index)
            .step_by(self.count)
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn env<'a>(vars: &'a [(&str, &str)]) -> impl Fn(&str) -> Option<String> + 'a {
        |name| {
            vars.iter()
                .find(|(k, _)| *k == name)
                .map(|(_, v)| v.to_string())
        }
    }

    #[test]
    fn the_flag_comes_first_then_slurm_then_kubernetes() {
        let slurm = [
            ("SLURM_ARRAY_TASK_ID", "5"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
            ("SLURM_ARRAY_TASK_MIN", "3"),
            ("JOB_COMPLETION_INDEX", "1"),
        ];
        let shard = |flag, completions, vars| Shard::resolve(flag, completions, env(vars));
        assert_eq!(
            shard(Some("1/3"), None, &slurm).unwrap(),
            Shard { index: 1, count: 3 }
        );
        assert_eq!(
            shard(None, None, &slurm).unwrap(),
            Shard { index: 2, count: 4 }
        );
        let k8s = [("JOB_COMPLETION_INDEX", "1")];
        assert_eq!(
            shard(None, Some(2), &k8s).unwrap(),
            Shard { index: 1, count: 2 }
        );
        assert_eq!(shard(None, None, &[]).unwrap(), Shard::WHOLE);
        for (flag, completions, vars, why) in [
            (Some("3/3"), None, &[][..], "out of range"),
            (Some("1-3"), None, &[][..], "must be K/N"),
            (None, None, &k8s[..], "--shard-count"),
            (
                None,
                None,
                &[("SLURM_ARRAY_TASK_ID", "x")][..],
                "not a number",
            ),
            (
                None,
                None,
                &[("SLURM_ARRAY_TASK_ID", "1")][..],
                "COUNT is not",
            ),
        ] {
            let e = shard(flag, completions, vars).unwrap_err().to_string();
            assert!(e.contains(why), "{e}");
        }
    }

    #[test]
    fn shards_split_the_plan_between_them() {
        let planned: Vec<usize> = (0..10).collect();
        let parts: Vec<Vec<&usize>> = (0..3)
            .map(|index| Shard { index, count: 3 }.take(&planned))
            .collect();
        assert_eq!(parts[1], [&1, &4, &7]);
        let mut all: Vec<usize> = parts.into_iter().flatten().copied().collect();
        all.sort();
        assert_eq!(all, planned);
    }
}
