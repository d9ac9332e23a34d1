//! Shards: the I-th of N parts of a job that a batch system (Slurm array jobs, Kubernetes
//! Indexed Jobs) runs on many machines, each part computed exactly as the whole job would
//! compute it, so the merged result equals a one-machine run byte for byte.

use std::ops::Range;

/// The I-th (from 0) of N shards.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ShardSpec {
    pub index: u32,
    pub count: u32,
}

/// Most shards of one job (each writes a file; the merge opens them all).
pub const MAX_SHARDS: u32 = 100_000;

/// A `--shard` value that names no shard.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("--shard {text:?}: {reason}")]
pub struct BadShard {
    pub text: String,
    pub reason: String,
}

/// Where the scheduler's environment says which task this is.
pub trait TaskEnvironment {
    fn var(&self, name: &str) -> Option<String>;
}

/// The process's own environment.
pub struct ProcessEnvironment;

impl TaskEnvironment for ProcessEnvironment {
    fn var(&self, name: &str) -> Option<String> {
        std::env::var(name).ok()
    }
}

impl ShardSpec {
    pub fn new(index: u32, count: u32) -> Result<Self, String> {
        if count == 0 || count > MAX_SHARDS {
            return Err(format!(
                "the shard count must be 1 to {MAX_SHARDS}, got {count}"
            ));
        }
        if index >= count {
            return Err(format!(
                "the shard index counts from 0 and must be below the count {count}, got {index}"
            ));
        }
        Ok(Self { index, count })
    }

    /// Parses `I/N`, where `I` may be `auto` (the task's index from the scheduler:
    /// `SLURM_ARRAY_TASK_ID` less `SLURM_ARRAY_TASK_MIN`, or Kubernetes'
    /// `JOB_COMPLETION_INDEX`) and `N` may be `auto` (Slurm's `SLURM_ARRAY_TASK_COUNT`);
    /// plain `auto` is `auto/auto`.
    pub fn parse(text: &str, env: &dyn TaskEnvironment) -> Result<Self, BadShard> {
        let bad = |reason: String| BadShard {
            text: text.to_owned(),
            reason,
        };
        let trimmed = text.trim();
        let (index, count) = match trimmed {
            "auto" => ("auto", "auto"),
            _ => trimmed.split_once('/').ok_or_else(|| {
                bad("expected I/N (the I-th of N shards, from 0), auto/N or auto".into())
            })?,
        };
        let count = match count.trim() {
            "auto" => scheduler_count(env).map_err(bad)?,
            n => parse_number(n, "N").map_err(bad)?,
        };
        let index = match index.trim() {
            "auto" => scheduler_index(env).map_err(bad)?,
            i => parse_number(i, "I").map_err(bad)?,
        };
        Self::new(index, count).map_err(bad)
    }

    /// This shard's part of `0..len` when every item costs the same.
    pub fn even_range(&self, len: usize) -> Range<usize> {
        let at = |k: u32| (len as u128 * k as u128 / self.count as u128) as usize;
        at(self.index)..at(self.index + 1)
    }

    /// The file-name tag of this shard, `0003-of-0016`: sorts in index order.
    pub fn tag(&self) -> String {
        format!("{:04}-of-{:04}", self.index, self.count)
    }
}

impl std::fmt::Display for ShardSpec {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

fn parse_number(text: &str, what: &str) -> Result<u32, String> {
    text.parse()
        .map_err(|_| format!("{what} must be a whole number, got {text:?}"))
}

fn env_number(env: &dyn TaskEnvironment, name: &str) -> Result<Option<u32>, String> {
    env.var(name)
        .map(|v| {
            v.trim()
                .parse()
                .map_err(|_| format!("{name}={v:?} is not a whole number"))
        })
        .transpose()
}

/// The task's index from Slurm's or Kubernetes' environment.
fn scheduler_index(env: &dyn TaskEnvironment) -> Result<u32, String> {
    if let Some(id) = env_number(env, "SLURM_ARRAY_TASK_ID")? {
        let min = env_number(env, "SLURM_ARRAY_TASK_MIN")?.unwrap_or(0);
        return id.checked_sub(min).ok_or_else(|| {
            format!("SLURM_ARRAY_TASK_ID {id} is below SLURM_ARRAY_TASK_MIN {min}")
        });
    }
    env_number(env, "JOB_COMPLETION_INDEX")?.ok_or_else(|| {
        "I is auto but neither SLURM_ARRAY_TASK_ID (a Slurm array job) nor JOB_COMPLETION_INDEX \
         (a Kubernetes Indexed Job) is set"
            .into()
    })
}

/// The task count from Slurm's environment (Kubernetes does not give it: write `auto/N`).
fn scheduler_count(env: &dyn TaskEnvironment) -> Result<u32, String> {
    env_number(env, "SLURM_ARRAY_TASK_COUNT")?.ok_or_else(|| {
        "N is auto but SLURM_ARRAY_TASK_COUNT is not set (outside a Slurm array job, give N: \
         auto/N)"
            .into()
    })
}

/// A set of shards that is not one whole job.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum IncompleteShards {
    #[error("no shards to merge")]
    Empty,
    #[error("shard {index} of {count} is missing (found {found} of {count})")]
    Missing {
        index: u32,
        count: u32,
        found: usize,
    },
    #[error("shard {index} of {count} is present twice")]
    Duplicate { index: u32, count: u32 },
}

/// Checks that `specs`, sorted by index and all of one count, hold every index once.
pub fn check_indices(specs: &[ShardSpec]) -> Result<(), IncompleteShards> {
    let Some(first) = specs.first() else {
        return Err(IncompleteShards::Empty);
    };
    let (count, found) = (first.count, specs.len());
    let mut expected = 0u32;
    for s in specs {
        if s.index < expected {
            return Err(IncompleteShards::Duplicate {
                index: s.index,
                count,
            });
        }
        if s.index > expected {
            break;
        }
        expected += 1;
    }
    if expected != count {
        return Err(IncompleteShards::Missing {
            index: expected,
            count,
            found,
        });
    }
    Ok(())
}

/// The shard files of a folder cannot be listed.
#[derive(Debug, thiserror::Error)]
pub enum ListError {
    #[error("cannot read the folder {}", dir.display())]
    Unreadable {
        dir: std::path::PathBuf,
        #[source]
        cause: std::io::Error,
    },
    #[error(
        "{} holds no {what} (*.{extension}); make them with `{command} --shard I/N -o {}`",
        dir.display(),
        dir.display()
    )]
    Empty {
        dir: std::path::PathBuf,
        what: &'static str,
        extension: &'static str,
        /// The command that makes them ("hprt bake SCENE").
        command: &'static str,
    },
}

/// The files in `dir` whose extension is `extension`, sorted by name; an error naming the
/// folder and the `command` that makes them when there are none.
pub fn files_with_extension(
    dir: &std::path::Path,
    extension: &'static str,
    what: &'static str,
    command: &'static str,
) -> Result<Vec<std::path::PathBuf>, ListError> {
    let unreadable = |cause| ListError::Unreadable {
        dir: dir.to_owned(),
        cause,
    };
    let mut files = Vec::new();
    for entry in std::fs::read_dir(dir).map_err(unreadable)? {
        let path = entry.map_err(unreadable)?.path();
        if path.extension().is_some_and(|e| e == extension) {
            files.push(path);
        }
    }
    files.sort();
    if files.is_empty() {
        return Err(ListError::Empty {
            dir: dir.to_owned(),
            what,
            extension,
            command,
        });
    }
    Ok(files)
}

/// Splits items of the given costs into `count` consecutive ranges of about equal total
/// cost (each range's end is the first item whose cost prefix reaches its share). The split
/// depends only on `costs`, so every shard computes the same one on its own.
pub fn split_by_cost(costs: &[f64], count: u32) -> Vec<Range<usize>> {
    let total: f64 = costs.iter().sum();
    let mut bounds = vec![0usize];
    let mut prefix = 0.0;
    let mut item = 0;
    for k in 1..count {
        let goal = total * k as f64 / count as f64;
        while item < costs.len() && prefix + 0.5 * costs[item] < goal {
            prefix += costs[item];
            item += 1;
        }
        bounds.push(item.max(*bounds.last().unwrap_or(&0)));
    }
    bounds.push(costs.len());
    bounds.windows(2).map(|w| w[0]..w[1]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    struct Vars(HashMap<&'static str, &'static str>);

    impl TaskEnvironment for Vars {
        fn var(&self, name: &str) -> Option<String> {
            self.0.get(name).map(|v| v.to_string())
        }
    }

    fn vars(pairs: &[(&'static str, &'static str)]) -> Vars {
        Vars(pairs.iter().copied().collect())
    }

    #[test]
    fn explicit_and_scheduler_shards_parse() {
        let none = vars(&[]);
        assert_eq!(
            ShardSpec::parse("2/4", &none),
            Ok(ShardSpec::new(2, 4).unwrap())
        );
        for bad in ["4/4", "1/0", "x/2", "3", "auto", "auto/3", "-1/2"] {
            assert!(ShardSpec::parse(bad, &none).is_err(), "{bad}");
        }
        let slurm = vars(&[
            ("SLURM_ARRAY_TASK_ID", "7"),
            ("SLURM_ARRAY_TASK_MIN", "5"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
        ]);
        assert_eq!(
            ShardSpec::parse("auto", &slurm),
            Ok(ShardSpec::new(2, 4).unwrap())
        );
        let k8s = vars(&[("JOB_COMPLETION_INDEX", "3")]);
        assert_eq!(
            ShardSpec::parse("auto/8", &k8s),
            Ok(ShardSpec::new(3, 8).unwrap())
        );
        assert!(ShardSpec::parse("auto/3", &k8s).is_err(), "index 3 of 3");
    }

    #[test]
    fn incomplete_sets_are_named() {
        let specs = |indices: &[u32]| -> Vec<ShardSpec> {
            indices
                .iter()
                .map(|&i| ShardSpec::new(i, 3).unwrap())
                .collect()
        };
        assert_eq!(check_indices(&specs(&[0, 1, 2])), Ok(()));
        assert_eq!(
            check_indices(&specs(&[0, 2])),
            Err(IncompleteShards::Missing {
                index: 1,
                count: 3,
                found: 2
            })
        );
        assert_eq!(
            check_indices(&specs(&[0, 1])),
            Err(IncompleteShards::Missing {
                index: 2,
                count: 3,
                found: 2
            })
        );
        assert_eq!(
            check_indices(&specs(&[0, 1, 1, 2])),
            Err(IncompleteShards::Duplicate { index: 1, count: 3 })
        );
        assert_eq!(check_indices(&[]), Err(IncompleteShards::Empty));
    }

    #[test]
    fn even_ranges_tile_the_items() {
        for len in [0usize, 1, 5, 97] {
            for count in [1u32, 2, 3, 7] {
                let ranges: Vec<_> = (0..count)
                    .map(|i| ShardSpec::new(i, count).unwrap().even_range(len))
                    .collect();
                assert_eq!(ranges[0].start, 0);
                assert_eq!(ranges.last().unwrap().end, len);
                assert!(ranges.windows(2).all(|w| w[0].end == w[1].start));
            }
        }
    }

    #[test]
    fn cost_split_tiles_and_balances() {
        // 60 cheap items, then 40 dear ones (220 in all): by count 2 shards would split at 50
        // (50 against 170), by cost at 72 (108 against 112).
        let costs: Vec<f64> = (0..100).map(|i| if i < 60 { 1.0 } else { 4.0 }).collect();
        let ranges = split_by_cost(&costs, 2);
        assert_eq!(ranges, vec![0..72, 72..100]);
        for count in [1u32, 3, 5, 100, 150] {
            let ranges = split_by_cost(&costs, count);
            assert_eq!(ranges.len(), count as usize);
            assert_eq!(ranges[0].start, 0);
            assert_eq!(ranges.last().unwrap().end, 100);
            assert!(ranges.windows(2).all(|w| w[0].end == w[1].start));
            let total: f64 = costs.iter().sum();
            let largest_item = 4.0;
            for r in &ranges {
                let cost: f64 = costs[r.clone()].iter().sum();
                assert!(
                    (cost - total / count as f64).abs() <= largest_item,
                    "{count}: {r:?} costs {cost}"
                );
            }
        }
    }
}
