//! Designs of a what-if study: the scene overrides of every run, and how the runs are split
//! into shards for a batch scheduler.
//!
//! A design is either a Cartesian grid of listed values (`--vary KEY=V1,V2,...`, the last key
//! varying fastest) or a sample of ranges (`--sample lhs:N|mc:N --range KEY=LO:HI`):
//! - Monte Carlo: u_dk ~ U(0, 1) independently, x_dk = LO_d + u_dk (HI_d - LO_d);
//! - Latin hypercube: per key d a random permutation pi_d of 0..N and
//!   u_dk = (pi_d(k) + U(0, 1)) / N, so each of the N equal strata of every range holds
//!   exactly one run (McKay, Beckman and Conover 1979).
//!
//! The stream is ChaCha8 seeded with `--seed` (default 1): the same command gives the same
//! runs on every machine and in every shard. Values are written as the shortest decimal that
//! reads back to the same f64, and enter the scene as `--set KEY=VALUE`.
//!
//! Shard I of N (1-based) holds the runs k (0-based) with k mod N = I - 1: a deterministic
//! partition that spreads every part of a grid over all shards.

use rand_chacha::rand_core::{RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::path::PathBuf;

/// A design that cannot be used, with the argument or variable at fault.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum DesignError {
    #[error("{arg} '{value}': {problem} (expected {expected})")]
    Argument {
        arg: &'static str,
        value: String,
        problem: String,
        expected: &'static str,
    },
    #[error("{0}")]
    Design(String),
    #[error("environment variable {var}='{value}': {problem}")]
    Environment {
        var: &'static str,
        value: String,
        problem: String,
    },
}

/// Why the parts of a sharded study (`sweep-merge`) cannot be merged: the file and what is
/// wrong with it.
#[derive(Debug, thiserror::Error)]
pub enum PartError {
    #[error("{path}: cannot read: {reason}")]
    Read { path: PathBuf, reason: String },
    #[error(
        "{path}: no part-*.json in this directory (expected the --out PART_DIR of sweep shards)"
    )]
    NoParts { path: PathBuf },
    #[error("{path}: not a sweep part ({reason}; expected the part-I-of-N.json a `sweep --shard` writes)")]
    NotAPart { path: PathBuf, reason: String },
    #[error("{path}: {what} {theirs} differs from {first}'s {ours}: the parts are not one study")]
    Differs {
        path: PathBuf,
        first: PathBuf,
        what: &'static str,
        theirs: String,
        ours: String,
    },
    #[error("{path}: shard {index}/{count} given twice (also {other})")]
    Twice {
        path: PathBuf,
        index: usize,
        count: usize,
        other: PathBuf,
    },
    #[error("{path}: shard {index}/{count} does not hold its runs (k mod {count} = {index} - 1 of the design's {total}): {problem}")]
    Runs {
        path: PathBuf,
        index: usize,
        count: usize,
        total: usize,
        problem: String,
    },
    #[error("sweep-merge: shard(s) {0} missing (their part-I-of-N.json files)")]
    Missing(String),
}

/// One listed key of a grid and its values (TOML literals, as written).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Vary {
    pub key: String,
    pub values: Vec<String>,
}

/// One sampled key: uniform over [lo, hi].
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Range {
    pub key: String,
    pub lo: f64,
    pub hi: f64,
}

/// How a sample is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// Latin hypercube.
    Lhs,
    /// Plain Monte Carlo.
    Mc,
}

/// The runs of a study.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum Design {
    Grid {
        vary: Vec<Vary>,
    },
    Sample {
        method: Method,
        runs: usize,
        ranges: Vec<Range>,
        seed: u64,
    },
}

fn argument(arg: &'static str, value: &str, problem: &str, expected: &'static str) -> DesignError {
    DesignError::Argument {
        arg,
        value: value.to_string(),
        problem: problem.to_string(),
        expected,
    }
}

/// Parses `KEY=V1,V2,...`.
pub fn parse_vary(arg: &str) -> Result<Vary, DesignError> {
    let bad = |p: &str| argument("--vary", arg, p, "KEY=V1,V2,...");
    let (k, v) = arg.split_once('=').ok_or_else(|| bad("no '='"))?;
    let key = k.trim();
    if key.is_empty() {
        return Err(bad("empty key"));
    }
    let values: Vec<String> = v.split(',').map(|s| s.trim().to_string()).collect();
    if values.iter().any(|s| s.is_empty()) {
        return Err(bad("empty value"));
    }
    // the same run twice is a typing error (60,60 for 60,80), also spelled two ways (80,8e1:
    // values compare as the scene reads them); a range belongs to --range
    let mut seen = std::collections::HashSet::new();
    let same = |x: &str| {
        super::overrides::parse_value(x).map_or_else(
            |_| x.to_string(),
            |v| match v {
                toml::Value::Integer(i) => format!("{}", i as f64),
                toml::Value::Float(f) => format!("{f}"),
                other => other.to_string(),
            },
        )
    };
    if let Some(twice) = values.iter().find(|x| !seen.insert(same(x))) {
        return Err(bad(&format!("the value '{twice}' is given twice")));
    }
    let numeric_range = |x: &str| {
        x.split_once(':').is_some_and(|(lo, hi)| {
            lo.trim().parse::<f64>().is_ok() && hi.trim().parse::<f64>().is_ok()
        })
    };
    if values.iter().any(|x| numeric_range(x)) {
        return Err(bad(
            "a value is a range LO:HI (ranges belong to --sample's --range KEY=LO:HI)",
        ));
    }
    Ok(Vary {
        key: key.to_string(),
        values,
    })
}

/// Parses `KEY=LO:HI` (finite numbers, LO < HI).
pub fn parse_range(arg: &str) -> Result<Range, DesignError> {
    let bad = |p: &str| argument("--range", arg, p, "KEY=LO:HI with finite LO < HI");
    let (k, v) = arg.split_once('=').ok_or_else(|| bad("no '='"))?;
    let key = k.trim();
    if key.is_empty() {
        return Err(bad("empty key"));
    }
    let (lo, hi) = v.split_once(':').ok_or_else(|| bad("no ':'"))?;
    let num = |s: &str| {
        s.trim()
            .parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| bad(&format!("'{}' is not a finite number", s.trim())))
    };
    let (lo, hi) = (num(lo)?, num(hi)?);
    if lo >= hi {
        return Err(bad("LO is not below HI"));
    }
    Ok(Range {
        key: key.to_string(),
        lo,
        hi,
    })
}

/// A count or index as given: `s` (trimmed) as a whole number, or what is wrong with it (too
/// large for this machine's integers, or not a whole number).
fn whole_number(s: &str) -> Result<usize, String> {
    let s = s.trim();
    s.parse::<usize>().map_err(|e| match e.kind() {
        std::num::IntErrorKind::PosOverflow => format!("too large (at most {})", usize::MAX),
        _ => "not a whole number".to_string(),
    })
}

/// [`whole_number`] with the refused text named in its problem ("'x' is not a whole number").
fn whole_number_named(s: &str) -> Result<usize, String> {
    whole_number(s).map_err(|p| format!("'{}' is {p}", s.trim()))
}

/// Parses `lhs:N` or `mc:N` (N >= 2).
pub fn parse_sample(arg: &str) -> Result<(Method, usize), DesignError> {
    let bad = |p: &str| argument("--sample", arg, p, "lhs:N or mc:N with N >= 2");
    let (m, n) = arg.split_once(':').ok_or_else(|| bad("no ':'"))?;
    let method = match m.trim() {
        "lhs" => Method::Lhs,
        "mc" => Method::Mc,
        other => return Err(bad(&format!("unknown method '{other}'"))),
    };
    let n = whole_number_named(n).map_err(|p| bad(&format!("N: {p}")))?;
    if n < 2 {
        return Err(bad("fewer than 2 runs"));
    }
    Ok((method, n))
}

impl Design {
    /// The design of the command line: a grid from `vary`, or a sample of `ranges`; each key
    /// at most once, one kind only.
    pub fn from_args(
        vary: &[String],
        sample: Option<&str>,
        ranges: &[String],
        seed: Option<u64>,
    ) -> Result<Self, DesignError> {
        let design = match sample {
            None => {
                if !ranges.is_empty() || seed.is_some() {
                    return Err(DesignError::Design(
                        "--range and --seed belong to a sample: give --sample lhs:N or mc:N".into(),
                    ));
                }
                if vary.is_empty() {
                    return Err(DesignError::Design(
                        "give at least one --vary KEY=V1,V2,... or a --sample with --range KEY=LO:HI".into(),
                    ));
                }
                Design::Grid {
                    vary: vary
                        .iter()
                        .map(|v| parse_vary(v))
                        .collect::<Result<_, _>>()?,
                }
            }
            Some(s) => {
                if !vary.is_empty() {
                    return Err(DesignError::Design(
                        "--vary (a grid) and --sample cannot be combined; fix a key with --set"
                            .into(),
                    ));
                }
                let (method, runs) = parse_sample(s)?;
                if ranges.is_empty() {
                    return Err(DesignError::Design(
                        "--sample needs at least one --range KEY=LO:HI".into(),
                    ));
                }
                Design::Sample {
                    method,
                    runs,
                    ranges: ranges
                        .iter()
                        .map(|r| parse_range(r))
                        .collect::<Result<_, _>>()?,
                    seed: seed.unwrap_or(1),
                }
            }
        };
        let keys = design.keys();
        // where and within what a study runs is no input of its runs (`limits.max_hours=1,2`
        // and `rom.cache_dir=/a,/b` ran)
        if let Some(k) = keys.iter().find(|k| {
            ["limits", "rom.cache_dir"]
                .iter()
                .any(|o| super::overrides::within(o, k) || super::overrides::within(k, o))
        }) {
            return Err(DesignError::Design(format!(
                "'{k}' is not an input of the runs (limits and the cache directory hold for the whole study): fix it with --set"
            )));
        }
        // a key twice, or a table and a key inside it (the run's value would hang on their
        // order)
        for (i, k) in keys.iter().enumerate() {
            if let Some(other) = keys[..i]
                .iter()
                .find(|o| super::overrides::within(o, k) || super::overrides::within(k, o))
            {
                let k = if other.len() > k.len() { other } else { k };
                return Err(DesignError::Design(format!("key '{k}' given twice")));
            }
        }
        Ok(design)
    }

    /// Refuses a `--set KEY=VALUE` whose key the design varies: the varied value would
    /// silently replace the fixed one in every run.
    pub fn check_fixed(&self, sets: &[String]) -> Result<(), DesignError> {
        let keys = self.keys();
        for s in sets {
            let key = s.split_once('=').map_or(s.as_str(), |(k, _)| k);
            let key = key.split('.').map(str::trim).collect::<Vec<_>>().join(".");
            let key = key.as_str();
            // a fixed table holding a varied key is the same conflict
            if let Some(varied) = keys
                .iter()
                .find(|k| super::overrides::within(key, k) || super::overrides::within(k, key))
            {
                return Err(DesignError::Argument {
                    arg: "--set",
                    value: s.clone(),
                    problem: format!("the design varies '{varied}' too"),
                    expected: "a key fixed by --set or varied by --vary/--range, not both",
                });
            }
        }
        Ok(())
    }

    /// The design as the command line gives it: `--vary KEY=V1,V2 ...` or `--sample lhs:N
    /// --range KEY=LO:HI ... --seed S`.
    pub fn describe(&self) -> String {
        match self {
            Design::Grid { vary } => vary
                .iter()
                .map(|v| format!("--vary {}={}", v.key, v.values.join(",")))
                .collect::<Vec<_>>()
                .join(" "),
            Design::Sample {
                method,
                runs,
                ranges,
                seed,
            } => {
                let m = match method {
                    Method::Lhs => "lhs",
                    Method::Mc => "mc",
                };
                let r: Vec<String> = ranges
                    .iter()
                    .map(|r| format!("--range {}={}:{}", r.key, r.lo, r.hi))
                    .collect();
                format!("--sample {m}:{runs} {} --seed {seed}", r.join(" "))
            }
        }
    }

    /// The varied keys, in order.
    pub fn keys(&self) -> Vec<String> {
        match self {
            Design::Grid { vary } => vary.iter().map(|v| v.key.clone()).collect(),
            Design::Sample { ranges, .. } => ranges.iter().map(|r| r.key.clone()).collect(),
        }
    }

    /// Number of runs (saturating).
    pub fn len(&self) -> usize {
        match self {
            Design::Grid { vary } => vary
                .iter()
                .try_fold(1usize, |n, v| n.checked_mul(v.values.len()))
                .unwrap_or(usize::MAX),
            Design::Sample { runs, .. } => *runs,
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Whether the runs are a random sample (probabilities and sensitivities apply).
    pub fn is_sample(&self) -> bool {
        matches!(self, Design::Sample { .. })
    }

    /// The values of every key for every run (run-major).
    pub fn runs(&self) -> Vec<Vec<String>> {
        match self {
            Design::Grid { vary } => {
                let mut combos: Vec<Vec<String>> = vec![vec![]];
                for v in vary {
                    combos = combos
                        .into_iter()
                        .flat_map(|c| {
                            v.values.iter().map(move |x| {
                                let mut c = c.clone();
                                c.push(x.clone());
                                c
                            })
                        })
                        .collect();
                }
                combos
            }
            Design::Sample {
                method,
                runs,
                ranges,
                seed,
            } => {
                let u = unit_sample(*method, *runs, ranges.len(), *seed);
                (0..*runs)
                    .map(|k| {
                        ranges
                            .iter()
                            .enumerate()
                            .map(|(d, r)| toml_float(r.lo + u[d][k] * (r.hi - r.lo)))
                            .collect()
                    })
                    .collect()
            }
        }
    }
}

/// `x` as a TOML literal: the shortest decimal that reads back as `x`, in exponent form when
/// the plain form would be long (1.3e308 prints 309 digits plainly, which TOML reads as an
/// integer out of range).
fn toml_float(x: f64) -> String {
    let plain = format!("{x}");
    if plain.len() > 24 {
        format!("{x:e}")
    } else {
        plain
    }
}

/// A uniform double in [0, 1) from the top 53 bits of a 64-bit draw.
fn unit(rng: &mut ChaCha8Rng) -> f64 {
    (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64
}

/// Points u[d][k] in [0, 1)^dims of a Monte Carlo or Latin hypercube sample of n runs. The
/// permutation is Fisher-Yates with j = floor(U (i + 1)) (the bias of a 53-bit U is below
/// 1e-12 for every n this tool can run).
fn unit_sample(method: Method, n: usize, dims: usize, seed: u64) -> Vec<Vec<f64>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..dims)
        .map(|_| match method {
            Method::Mc => (0..n).map(|_| unit(&mut rng)).collect(),
            Method::Lhs => {
                let mut perm: Vec<usize> = (0..n).collect();
                for i in (1..n).rev() {
                    let j = ((unit(&mut rng) * (i + 1) as f64) as usize).min(i);
                    perm.swap(i, j);
                }
                perm.iter()
                    .map(|&p| (p as f64 + unit(&mut rng)) / n as f64)
                    .collect()
            }
        })
        .collect()
}

/// Shard `index` (1-based) of `count`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Shard {
    pub index: usize,
    pub count: usize,
}

impl Shard {
    /// Parses `I/N` with 1 <= I <= N, given as `flag` (for the messages).
    pub fn parse(flag: &'static str, arg: &str) -> Result<Self, DesignError> {
        let bad = |p: &str| argument(flag, arg, p, "I/N with 1 <= I <= N");
        let (i, n) = arg.split_once('/').ok_or_else(|| bad("no '/'"))?;
        let num = |s: &str| whole_number_named(s).map_err(|p| bad(&p));
        let (index, count) = (num(i)?, num(n)?);
        if index == 0 || index > count {
            return Err(bad("I outside 1..N"));
        }
        Ok(Shard { index, count })
    }

    /// The shard a scheduler gives this process, from the environment `var`:
    /// - Slurm job arrays: SLURM_ARRAY_TASK_ID within SLURM_ARRAY_TASK_MIN..=MAX (step 1; any
    ///   first index, `--array=0-2` and `--array=1-3` alike): I = ID - MIN + 1, N = MAX - MIN + 1;
    /// - Kubernetes Indexed Jobs: JOB_COMPLETION_INDEX (0-based) with the count `shards`
    ///   (the Job's `completions`): I = INDEX + 1, N = shards.
    ///
    /// None when neither is set.
    pub fn from_env(
        var: &dyn Fn(&str) -> Option<String>,
        shards: Option<usize>,
    ) -> Result<Option<Self>, DesignError> {
        Self::from_env_as(var, (shards, "--shards"), "--shard")
    }

    /// [`Shard::from_env`] for the command whose explicit form is `flag` I/N (`--shard` of a
    /// sweep, `--component` of `rom`), whose count `shards` is `count_name` (`--shards`, the
    /// engine's components): the messages name them. Both schedulers' task variables set at
    /// once are refused (which one placed this process is not known).
    pub fn from_env_as(
        var: &dyn Fn(&str) -> Option<String>,
        (shards, count_name): (Option<usize>, &str),
        flag: &str,
    ) -> Result<Option<Self>, DesignError> {
        if let (Some(slurm), Some(_)) = (var("SLURM_ARRAY_TASK_ID"), var("JOB_COMPLETION_INDEX")) {
            return Err(DesignError::Environment {
                var: "SLURM_ARRAY_TASK_ID",
                value: slurm,
                problem: format!(
                    "JOB_COMPLETION_INDEX is set as well (a Slurm array task and a Kubernetes Indexed Job at once): unset one, or give {flag} I/N"
                ),
            });
        }
        let number = |name: &'static str| -> Result<Option<usize>, DesignError> {
            match var(name) {
                None => Ok(None),
                Some(v) => whole_number(&v)
                    .map(Some)
                    .map_err(|problem| DesignError::Environment {
                        var: name,
                        value: v.clone(),
                        problem,
                    }),
            }
        };
        if let Some(id) = number("SLURM_ARRAY_TASK_ID")? {
            let missing = |name: &'static str| DesignError::Environment {
                var: name,
                value: String::new(),
                problem: format!("not set beside SLURM_ARRAY_TASK_ID (give {flag} I/N)"),
            };
            let min =
                number("SLURM_ARRAY_TASK_MIN")?.ok_or_else(|| missing("SLURM_ARRAY_TASK_MIN"))?;
            let max =
                number("SLURM_ARRAY_TASK_MAX")?.ok_or_else(|| missing("SLURM_ARRAY_TASK_MAX"))?;
            if let Some(step) = number("SLURM_ARRAY_TASK_STEP")?.filter(|&s| s != 1) {
                return Err(DesignError::Environment {
                    var: "SLURM_ARRAY_TASK_STEP",
                    value: step.to_string(),
                    problem: format!("the array must be a contiguous range like --array=0-9 (or give {flag} I/N)"),
                });
            }
            if id < min || id > max {
                return Err(DesignError::Environment {
                    var: "SLURM_ARRAY_TASK_ID",
                    value: id.to_string(),
                    problem: format!("outside SLURM_ARRAY_TASK_MIN..MAX = {min}..{max}"),
                });
            }
            let count = (max - min)
                .checked_add(1)
                .ok_or_else(|| DesignError::Environment {
                    var: "SLURM_ARRAY_TASK_MAX",
                    value: max.to_string(),
                    problem: format!(
                        "the range {min}..{max} holds more tasks than this machine counts"
                    ),
                })?;
            if let Some(c) = number("SLURM_ARRAY_TASK_COUNT")?.filter(|&c| c != count) {
                return Err(DesignError::Environment {
                    var: "SLURM_ARRAY_TASK_COUNT",
                    value: c.to_string(),
                    problem: format!(
                        "the array has gaps ({c} tasks in {min}..{max}): use a contiguous range or {flag} I/N"
                    ),
                });
            }
            return Ok(Some(Shard {
                index: id - min + 1,
                count,
            }));
        }
        if let Some(idx) = number("JOB_COMPLETION_INDEX")? {
            let count = shards.ok_or_else(|| DesignError::Environment {
                var: "JOB_COMPLETION_INDEX",
                value: idx.to_string(),
                problem: "give the number of shards (the Job's completions) with --shards N".into(),
            })?;
            if idx >= count {
                return Err(DesignError::Environment {
                    var: "JOB_COMPLETION_INDEX",
                    value: idx.to_string(),
                    problem: format!(
                        "not below {count_name} ({count}: indices 0 to {})",
                        count - 1
                    ),
                });
            }
            return Ok(Some(Shard {
                index: idx + 1,
                count,
            }));
        }
        Ok(None)
    }

    /// How many of `total` runs this shard holds.
    pub fn len(&self, total: usize) -> usize {
        if total < self.index {
            0
        } else {
            (total - self.index) / self.count + 1
        }
    }

    /// The runs (0-based indices among `total`) of this shard: k with k mod N = I - 1.
    pub fn runs(&self, total: usize) -> Vec<usize> {
        (self.index - 1..total).step_by(self.count).collect()
    }

    /// Whether run `k` belongs to this shard.
    pub fn holds(&self, k: usize) -> bool {
        k % self.count == self.index - 1
    }
}

/// The process's environment variable `name` for [`Shard::from_env`]: a value that is not
/// UTF-8 is the value with its bad bytes replaced (refused as no whole number, naming the
/// variable); it was taken as unset, and the task ran the whole unsharded sweep.
pub fn scheduler_var(name: &str) -> Option<String> {
    std::env::var_os(name).map(|v| v.to_string_lossy().into_owned())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn env(pairs: &[(&str, &str)]) -> impl Fn(&str) -> Option<String> {
        let m: std::collections::HashMap<String, String> = pairs
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect();
        move |k: &str| m.get(k).cloned()
    }

    /// Regression: an index beyond the machine's integers was called "not a whole number"
    /// (`--component 99999999999999999999/3`); it is now "too large", and a word still "not a
    /// whole number", in a shard, a sample's N and a scheduler's variable.
    #[test]
    fn regression_a_number_too_large_is_called_so() {
        let e = Shard::parse("--component", "99999999999999999999/3")
            .unwrap_err()
            .to_string();
        assert!(e.contains("is too large"), "{e}");
        let e = Shard::parse("--shard", "x/3").unwrap_err().to_string();
        assert!(e.contains("'x' is not a whole number"), "{e}");
        let e = parse_sample("lhs:99999999999999999999")
            .unwrap_err()
            .to_string();
        assert!(e.contains("is too large"), "{e}");
        let e = whole_number(" 12 ").unwrap();
        assert_eq!(e, 12);
    }

    /// Regression (session 70's hostile sweep): `--vary limits.max_hours=1,2` and
    /// `--vary rom.cache_dir=/a,/b` ran (the second wrote a cache into each directory).
    #[test]
    fn regression_limits_and_the_cache_directory_are_not_varied() {
        for arg in [
            "limits.max_hours=1,2",
            "rom.cache_dir=/a,/b",
            "limits={max_hours=1},{max_hours=2}",
        ] {
            let e = Design::from_args(&[arg.into()], None, &[], None)
                .unwrap_err()
                .to_string();
            assert!(e.contains("is not an input of the runs"), "{arg}: {e}");
        }
        assert!(Design::from_args(&["rom.band_hz=4000,5000".into()], None, &[], None).is_ok());
    }

    /// Regression: a value given twice in two spellings (80,8e1 or 80,80.0) ran twice.
    #[test]
    fn regression_a_value_spelled_twice_is_refused() {
        for arg in ["k=80,8e1", "k=80,80.0", "k=a,\"a\""] {
            let e = parse_vary(arg).unwrap_err().to_string();
            assert!(e.contains("is given twice"), "{arg}: {e}");
        }
        assert!(parse_vary("k=80,81,8e0").is_ok());
    }

    /// Regression: `--set` of a table that holds a varied key (`--set 'a={b=1}' --vary
    /// a.b=1,2`) passed the fixed-or-varied check, which compared whole keys only.
    #[test]
    fn regression_a_fixed_table_holding_a_varied_key_is_refused() {
        let d = Design::from_args(
            &["piston.thermal.liner_temp_c=100,110".into()],
            None,
            &[],
            None,
        )
        .unwrap();
        for set in [
            "piston.thermal={liner_temp_c=130.0}",
            "piston.thermal.liner_temp_c=1",
            "piston=x",
        ] {
            let e = d.check_fixed(&[set.into()]).unwrap_err().to_string();
            assert!(e.contains("the design varies"), "{set}: {e}");
        }
        assert!(d
            .check_fixed(&["piston.thermal.liner_temp=1".into()])
            .is_ok());
        // the varied key is the one named
        let e = d
            .check_fixed(&["piston={mass_kg=1}".into()])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("the design varies 'piston.thermal.liner_temp_c'"),
            "{e}"
        );
        // varying a table and a key inside it is a key given twice
        let vary = [
            "cavitation={gap_mm=4},{gap_mm=50}".into(),
            "cavitation.gap_mm=6,7".into(),
        ];
        let e = Design::from_args(&vary, None, &[], None)
            .unwrap_err()
            .to_string();
        assert!(e.contains("'cavitation.gap_mm' given twice"), "{e}");
    }

    #[test]
    fn shards_partition_the_runs() {
        for total in [0, 1, 7, 25, 2000] {
            for count in [1, 2, 3, 7, 40] {
                let mut seen = vec![0; total];
                for index in 1..=count {
                    let s = Shard { index, count };
                    assert_eq!(s.len(total), s.runs(total).len());
                    for k in s.runs(total) {
                        assert!(s.holds(k));
                        seen[k] += 1;
                    }
                }
                assert!(seen.iter().all(|&c| c == 1), "{total} {count}");
            }
        }
    }

    #[test]
    fn slurm_arrays_from_zero_and_from_one_give_the_same_shards() {
        for (lo, hi) in [(0, 2), (1, 3)] {
            for id in lo..=hi {
                let (i, mn, mx) = (id.to_string(), lo.to_string(), hi.to_string());
                let e = env(&[
                    ("SLURM_ARRAY_TASK_ID", &i),
                    ("SLURM_ARRAY_TASK_MIN", &mn),
                    ("SLURM_ARRAY_TASK_MAX", &mx),
                    ("SLURM_ARRAY_TASK_COUNT", "3"),
                ]);
                let s = Shard::from_env(&e, None).unwrap().unwrap();
                assert_eq!(
                    s,
                    Shard {
                        index: id - lo + 1,
                        count: 3
                    }
                );
            }
        }
        let gaps = env(&[
            ("SLURM_ARRAY_TASK_ID", "3"),
            ("SLURM_ARRAY_TASK_MIN", "1"),
            ("SLURM_ARRAY_TASK_MAX", "7"),
            ("SLURM_ARRAY_TASK_COUNT", "3"),
        ]);
        assert!(Shard::from_env(&gaps, None).is_err());
        let k8s = env(&[("JOB_COMPLETION_INDEX", "4")]);
        assert_eq!(
            Shard::from_env(&k8s, Some(5)).unwrap(),
            Some(Shard { index: 5, count: 5 })
        );
        assert!(Shard::from_env(&k8s, None).is_err());
        assert!(Shard::from_env(&k8s, Some(4)).is_err());
        assert_eq!(Shard::from_env(&env(&[]), Some(4)).unwrap(), None);
    }

    /// Regression: with a Slurm array's and a Kubernetes Indexed Job's task variables both
    /// set, the Slurm one was taken silently; a scheduler's bad value repeated itself in the
    /// message ("SLURM_ARRAY_TASK_ID='x': 'x' is not a whole number").
    #[test]
    fn regression_two_schedulers_at_once_are_refused() {
        let both = env(&[
            ("SLURM_ARRAY_TASK_ID", "1"),
            ("SLURM_ARRAY_TASK_MIN", "1"),
            ("SLURM_ARRAY_TASK_MAX", "3"),
            ("JOB_COMPLETION_INDEX", "0"),
        ]);
        let e = Shard::from_env(&both, Some(3)).unwrap_err().to_string();
        assert!(e.contains("JOB_COMPLETION_INDEX is set as well"), "{e}");
        // a range as wide as the machine's integers (its count wrapped to 0: a division by
        // zero)
        let wide = env(&[
            ("SLURM_ARRAY_TASK_ID", "0"),
            ("SLURM_ARRAY_TASK_MIN", "0"),
            ("SLURM_ARRAY_TASK_MAX", "18446744073709551615"),
        ]);
        assert!(Shard::from_env(&wide, None).is_err());
        let e = Shard::from_env(&env(&[("JOB_COMPLETION_INDEX", "x")]), Some(3))
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "environment variable JOB_COMPLETION_INDEX='x': not a whole number"
        );
        let e = Shard::from_env_as(
            &env(&[("JOB_COMPLETION_INDEX", "3")]),
            (Some(3), "the engine's components"),
            "--component",
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("not below the engine's components (3: indices 0 to 2)"),
            "{e}"
        );
    }

    #[test]
    fn latin_hypercube_puts_one_run_in_every_stratum() {
        let d = Design::from_args(
            &[],
            Some("lhs:50"),
            &["a=40:120".into(), "b=-1:1".into()],
            Some(7),
        )
        .unwrap();
        let runs = d.runs();
        assert_eq!(runs, d.runs(), "deterministic");
        for (dim, (lo, hi)) in [(40.0, 120.0), (-1.0, 1.0)].into_iter().enumerate() {
            let mut strata = vec![0; 50];
            for r in &runs {
                let x: f64 = r[dim].parse().unwrap();
                assert!((lo..hi).contains(&x));
                strata[((x - lo) / (hi - lo) * 50.0) as usize] += 1;
            }
            assert!(strata.iter().all(|&c| c == 1), "{strata:?}");
        }
        let other = Design::from_args(
            &[],
            Some("lhs:50"),
            &["a=40:120".into(), "b=-1:1".into()],
            Some(8),
        )
        .unwrap();
        assert_ne!(runs, other.runs(), "the seed matters");
    }

    #[test]
    fn bad_designs_name_the_argument() {
        let e = Design::from_args(&[], Some("lhs:1"), &["a=1:2".into()], None).unwrap_err();
        assert!(e.to_string().contains("--sample 'lhs:1'"), "{e}");
        let e = Design::from_args(&[], Some("lhs:5"), &["a=2:1".into()], None).unwrap_err();
        assert!(e.to_string().contains("--range 'a=2:1'"), "{e}");
        let e = Design::from_args(&["a=1,2".into()], Some("mc:5"), &[], None).unwrap_err();
        assert!(e.to_string().contains("cannot be combined"), "{e}");
        let e = Design::from_args(&["a=1,2".into(), "a=3".into()], None, &[], None).unwrap_err();
        assert!(e.to_string().contains("twice"), "{e}");
    }
}
