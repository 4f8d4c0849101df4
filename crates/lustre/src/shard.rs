//! `--shard K/N` and `--shard-count N` of the commands that split their work over machines
//! (`lustre fit`, `lustre bake`): which shard this process runs.
//!
//! `--shard K/N` names it directly (0 ≤ K < N). `--shard-count N` alone takes K from the job
//! array the process runs in: `JOB_COMPLETION_INDEX` (a Kubernetes Indexed Job), else
//! `SLURM_ARRAY_TASK_ID` minus `SLURM_ARRAY_TASK_MIN` (a SLURM array, which may start at 1).
//! Without either option the command does all the work itself, even inside a job array.
//!
//! `SLURM_ARRAY_TASK_MIN` makes an array numbered from 1 work, but an array resubmitted for some
//! of its tasks (`--array=3`) starts at that task, which would then read as shard 0: the SLURM
//! templates in `deploy/slurm` therefore pass `--shard $SLURM_ARRAY_TASK_ID/N` (arrays from 0).

use anyhow::{bail, Context, Result};

/// The shard options shared by the commands.
#[derive(Debug, Default, clap::Args)]
pub struct ShardArgs {
    /// Run only shard K of N (0-based) and write its part; assemble the parts with --merge.
    #[arg(long, value_name = "K/N", value_parser = parse_shard, conflicts_with = "shard_count")]
    pub shard: Option<(usize, usize)>,
    /// Split the work into N shards and take this process's index K from the job array:
    /// $JOB_COMPLETION_INDEX (Kubernetes Indexed Job) or $SLURM_ARRAY_TASK_ID (SLURM).
    #[arg(long = "shard-count", value_name = "N", value_parser = parse_count)]
    pub shard_count: Option<usize>,
}

impl ShardArgs {
    /// The shard `(K, N)` this process runs, `None` for all of the work.
    pub fn resolve(&self) -> Result<Option<(usize, usize)>> {
        self.resolve_with(|name| std::env::var(name).ok())
    }

    /// [`Self::resolve`] with the environment given as a lookup (for tests).
    pub fn resolve_with(
        &self,
        env: impl Fn(&str) -> Option<String>,
    ) -> Result<Option<(usize, usize)>> {
        if let Some(s) = self.shard {
            return Ok(Some(s));
        }
        let Some(n) = self.shard_count else {
            return Ok(None);
        };
        let read = |name: &str| -> Result<Option<usize>> {
            env(name)
                .map(|v| {
                    v.trim()
                        .parse::<usize>()
                        .with_context(|| format!("${name} = {v:?} is not a whole number ≥ 0"))
                })
                .transpose()
        };
        let k = if let Some(k) = read("JOB_COMPLETION_INDEX")? {
            k
        } else if let Some(id) = read("SLURM_ARRAY_TASK_ID")? {
            let min = read("SLURM_ARRAY_TASK_MIN")?.unwrap_or(0);
            match id.checked_sub(min) {
                Some(k) => k,
                None => bail!("$SLURM_ARRAY_TASK_ID {id} is below $SLURM_ARRAY_TASK_MIN {min}"),
            }
        } else {
            bail!(
                "--shard-count {n} needs the shard index from $JOB_COMPLETION_INDEX (Kubernetes \
                 Indexed Job) or $SLURM_ARRAY_TASK_ID (SLURM array); neither is set (outside a \
                 job array, give --shard K/{n})"
            );
        };
        if k >= n {
            bail!("shard index {k} from the job array is not below --shard-count {n}");
        }
        Ok(Some((k, n)))
    }
}

/// Parses `K/N` with 0 ≤ K < N.
fn parse_shard(s: &str) -> std::result::Result<(usize, usize), String> {
    let bad = || format!("{s:?}: expected K/N with whole numbers 0 ≤ K < N, e.g. 0/4");
    let (k, n) = s.split_once('/').ok_or_else(bad)?;
    let (k, n) = (
        k.trim().parse::<usize>().map_err(|_| bad())?,
        n.trim().parse::<usize>().map_err(|_| bad())?,
    );
    if k >= n {
        return Err(bad());
    }
    Ok((k, n))
}

/// Parses a shard count ≥ 1.
fn parse_count(s: &str) -> std::result::Result<usize, String> {
    match s.trim().parse::<usize>() {
        Ok(n) if n >= 1 => Ok(n),
        _ => Err(format!("{s:?}: expected a whole number ≥ 1")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn env<'a>(vars: &'a [(&'a str, &'a str)]) -> impl Fn(&str) -> Option<String> + 'a {
        move |name| {
            vars.iter()
                .find(|(n, _)| *n == name)
                .map(|(_, v)| v.to_string())
        }
    }

    #[test]
    fn shard_arguments_and_job_array_indices() {
        assert_eq!(parse_shard("2/4"), Ok((2, 4)));
        assert_eq!(parse_shard(" 0 / 1 "), Ok((0, 1)));
        for bad in ["4/4", "1", "a/2", "-1/2", "1/0", "/", "1/2/3"] {
            assert!(parse_shard(bad).is_err(), "{bad}");
        }
        assert!(parse_count("0").is_err() && parse_count("x").is_err());
        let none = ShardArgs::default();
        let k8s = [("JOB_COMPLETION_INDEX", "3")];
        assert_eq!(
            none.resolve_with(env(&k8s)).expect("ok"),
            None,
            "no option, no sharding"
        );
        let direct = ShardArgs {
            shard: Some((1, 4)),
            shard_count: None,
        };
        assert_eq!(direct.resolve_with(env(&k8s)).expect("ok"), Some((1, 4)));
        let counted = ShardArgs {
            shard: None,
            shard_count: Some(4),
        };
        assert_eq!(counted.resolve_with(env(&k8s)).expect("ok"), Some((3, 4)));
        let slurm = [("SLURM_ARRAY_TASK_ID", "4"), ("SLURM_ARRAY_TASK_MIN", "1")];
        assert_eq!(counted.resolve_with(env(&slurm)).expect("ok"), Some((3, 4)));
        let slurm0 = [("SLURM_ARRAY_TASK_ID", "2")];
        assert_eq!(
            counted.resolve_with(env(&slurm0)).expect("ok"),
            Some((2, 4))
        );
        for vars in [
            &[][..],
            &[("JOB_COMPLETION_INDEX", "4")][..],
            &[("JOB_COMPLETION_INDEX", "x")][..],
            &[("SLURM_ARRAY_TASK_ID", "0"), ("SLURM_ARRAY_TASK_MIN", "1")][..],
        ] {
            let e = counted.resolve_with(env(vars)).unwrap_err().to_string();
            assert!(e.contains("shard") || e.contains('$'), "{e}");
        }
    }
}
