//! `canif merge`: the shards of a campaign joined into the run they share.
//! Their checks are put back in the plan's order and judged once, by the
//! same [`verdict::judge`](crate::verdict::judge) a single run uses, so the
//! merged verdicts are those of one run of every shard's checks.

use std::fmt;
use std::path::PathBuf;

use canif_spec::Catalogue;

use super::part::{ShardPart, PART_FORMAT};
use super::{ProfileChecks, ProfileReport, RunMeta, RunReport};
use crate::verdict::NotRunReason;

/// Why shards cannot be merged.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum MergeError {
    /// No shard was given.
    Nothing,
    /// The shards were not cut from one run: `what` differs between two of them.
    Differ {
        what: &'static str,
        first: (PathBuf, String),
        other: (PathBuf, String),
    },
    /// The shards were judged by another catalogue than this canif's.
    Catalogue {
        file: PathBuf,
        theirs: String,
        ours: String,
    },
    /// A shard of the campaign is missing.
    Missing { index: u32, count: u32 },
    /// One shard given twice.
    Twice {
        index: u32,
        count: u32,
        first: PathBuf,
        other: PathBuf,
    },
    /// A part names a profile the catalogue does not have, or checks it cannot place.
    Malformed { file: PathBuf, what: String },
}

impl fmt::Display for MergeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MergeError::Nothing => f.write_str("no shard to merge"),
            MergeError::Differ { what, first, other } => write!(
                f,
                "the shards are not of one run: {what} is `{}` in {} but `{}` in {}",
                first.1,
                first.0.display(),
                other.1,
                other.0.display()
            ),
            MergeError::Catalogue { file, theirs, ours } => write!(
                f,
                "{} was judged by catalogue {theirs}; this canif's is {ours}: merge with the canif that ran the shards",
                file.display()
            ),
            MergeError::Missing { index, count } => write!(
                f,
                "shard {index}/{count} is missing: run `canif run … --shard {index}/{count}` and merge again"
            ),
            MergeError::Twice {
                index,
                count,
                first,
                other,
            } => write!(
                f,
                "shard {index}/{count} is given twice: {} and {}",
                first.display(),
                other.display()
            ),
            MergeError::Malformed { file, what } => write!(f, "{}: {what}", file.display()),
        }
    }
}

impl std::error::Error for MergeError {}

/// Joins every shard of one campaign (each part with the file it came from).
pub fn merge(
    catalogue: &Catalogue,
    parts: Vec<(PathBuf, ShardPart)>,
) -> Result<RunReport, MergeError> {
    let (first_file, first) = parts.first().ok_or(MergeError::Nothing)?;
    if first.meta.catalogue_sha256 != catalogue.sha256 {
        return Err(MergeError::Catalogue {
            file: first_file.clone(),
            theirs: first.meta.catalogue_sha256.clone(),
            ours: catalogue.sha256.clone(),
        });
    }
    every_shard_once(&parts)?;
    // What the campaign left out: each shard's lines, its share replaced by
    // the selection every shard has.
    let unsharded = first.selection.unsharded();
    let mut left_out: Vec<String> = Vec::new();
    if !unsharded.is_everything() {
        left_out.push(unsharded.describe());
    }
    for (_, part) in &parts {
        let share = part.selection.describe();
        add_new(&mut left_out, part.left_out.iter().filter(|l| **l != share));
    }
    let interrupted = parts.iter().any(|(_, p)| p.interrupted);
    let reason =
        NotRunReason::of_run(&left_out, interrupted).unwrap_or_else(|| unsharded.not_run());

    let mut profiles = Vec::new();
    for (n, profile_part) in first.profiles.iter().enumerate() {
        let name = &profile_part.profile;
        let profile = catalogue
            .profile(name)
            .ok_or_else(|| MergeError::Malformed {
                file: first_file.clone(),
                what: format!("profile `{name}` is not in this canif's catalogue"),
            })?;
        let mut checks = merged_checks(&parts, n, profile_part)?;
        checks.reach.left_out = reason.clone();
        profiles.push(ProfileReport::judged(catalogue, profile, checks));
    }

    let mut meta = RunMeta {
        shard: None,
        ..first.meta.clone()
    }
    .left_out(&left_out, interrupted);
    meta.started_unix = parts
        .iter()
        .map(|(_, p)| p.meta.started_unix)
        .min()
        .unwrap_or(0);
    for (_, part) in &parts[1..] {
        add_new(&mut meta.choices, &part.meta.choices);
        add_new(&mut meta.terminals, &part.meta.terminals);
    }
    let mut flaky: Vec<String> = Vec::new();
    add_new(&mut flaky, parts.iter().flat_map(|(_, p)| &p.flaky));
    Ok(RunReport {
        meta,
        profiles,
        // The shards ran side by side: the campaign took as long as the longest.
        wall_time_ms: parts
            .iter()
            .map(|(_, p)| u128::from(p.wall_time_ms))
            .max()
            .unwrap_or(0),
        interrupted,
        flaky,
        part: None,
    })
}

/// Every shard of the same format, each K of N once and none missing.
fn every_shard_once(parts: &[(PathBuf, ShardPart)]) -> Result<(), MergeError> {
    let Some((_, first)) = parts.first() else {
        return Err(MergeError::Nothing);
    };
    for (file, part) in parts {
        if part.format != PART_FORMAT {
            return Err(MergeError::Malformed {
                file: file.clone(),
                what: format!(
                    "a shard.json of format {}; this canif reads {PART_FORMAT}",
                    part.format
                ),
            });
        }
    }
    same_run(parts)?;
    let count = first.shard.count;
    let mut seen: Vec<Option<&PathBuf>> = vec![None; count as usize];
    for (file, part) in parts {
        if !(1..=count).contains(&part.shard.index) {
            return Err(MergeError::Malformed {
                file: file.clone(),
                what: format!("shard {}: shards count from 1 to N", part.shard),
            });
        }
        let slot = &mut seen[(part.shard.index - 1) as usize];
        if let Some(earlier) = slot {
            return Err(MergeError::Twice {
                index: part.shard.index,
                count,
                first: (*earlier).clone(),
                other: file.clone(),
            });
        }
        *slot = Some(file);
    }
    if let Some(gap) = seen.iter().position(Option::is_none) {
        return Err(MergeError::Missing {
            index: gap as u32 + 1,
            count,
        });
    }

    Ok(())
}

/// Profile `n`'s checks from every shard, in the plan's order, each failure
/// renumbered into the merged list, the reach of all of them together.
fn merged_checks(
    parts: &[(PathBuf, ShardPart)],
    n: usize,
    profile_part: &super::ProfilePart,
) -> Result<ProfileChecks, MergeError> {
    let name = &profile_part.profile;
    let mut placed = Vec::new();
    let mut checks = ProfileChecks {
        reach: profile_part.checks.reach.clone(),
        ..ProfileChecks::default()
    };
    for (file, part) in parts {
        let mine = &part.profiles[n];
        if mine.order.len() != mine.checks.checks.len() {
            return Err(MergeError::Malformed {
                file: file.clone(),
                what: format!(
                    "{name}: {} checks but {} places",
                    mine.checks.checks.len(),
                    mine.order.len()
                ),
            });
        }
        checks.tally += mine.checks.tally;
        checks.advisories.add(&mine.checks.advisories);
        let reach = &mut checks.reach;
        reach.here.extend(mine.checks.reach.here.iter().cloned());
        for (id, why) in &mine.checks.reach.unobserved {
            reach
                .unobserved
                .entry(id.clone())
                .or_insert_with(|| why.clone());
        }
        for (id, why) in &mine.checks.reach.not_applicable {
            reach
                .not_applicable
                .entry(id.clone())
                .or_insert_with(|| why.clone());
        }
        for (place, check) in mine.order.iter().zip(&mine.checks.checks) {
            let failure =
                match &check.result {
                    crate::verdict::CheckResult::Fail(finding) => match finding.failure {
                        Some(i) => Some(mine.checks.failures.get(i).ok_or_else(|| {
                            MergeError::Malformed {
                                file: file.clone(),
                                what: format!(
                                    "{name}: a check names failure {i}, which is not there"
                                ),
                            }
                        })?),
                        None => None,
                    },
                    _ => None,
                };
            placed.push((*place, check, failure));
        }
    }
    // The plan's order; the checks of one case stay in their shard's order.
    placed.sort_by_key(|(place, _, _)| *place);
    for (_, check, failure) in placed {
        let mut check = check.clone();
        if let (crate::verdict::CheckResult::Fail(finding), Some(failure)) =
            (&mut check.result, failure)
        {
            finding.failure = Some(checks.failures.len());
            checks.failures.push(failure.clone());
        }
        checks.checks.push(check);
    }
    Ok(checks)
}

/// Appends each of `items` that `into` does not hold yet, in order.
fn add_new<'a, T: PartialEq + Clone + 'a>(
    into: &mut Vec<T>,
    items: impl IntoIterator<Item = &'a T>,
) {
    for item in items {
        if !into.contains(item) {
            into.push(item.clone());
        }
    }
}

/// Every shard is of the same run: the same IUT, options, profiles and
/// number of shards.
fn same_run(parts: &[(PathBuf, ShardPart)]) -> Result<(), MergeError> {
    let traits = |part: &ShardPart| -> [(&'static str, String); 12] {
        let m = &part.meta;
        [
            ("the catalogue", m.catalogue_sha256.clone()),
            (
                "canif's version",
                format!("{} ({})", m.canif_version, m.canif_commit),
            ),
            ("the implementation under test", m.iut.clone()),
            ("the product", format!("{:?}", m.product)),
            ("the side", m.side.to_string()),
            ("the suite", format!("{:?}", m.suite)),
            ("the bus", m.bus.clone()),
            ("the seed", m.seed.to_string()),
            ("the master models", m.masters.join(", ")),
            ("the selection", part.selection.unsharded().flags()),
            (
                "the command line (but --shard, --report, --jobs, --trace)",
                part.command.join(" "),
            ),
            (
                "the shards and profiles",
                format!(
                    "{} shards of {}",
                    part.shard.count,
                    part.profiles
                        .iter()
                        .map(|p| p.profile.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            ),
        ]
    };
    let (first_file, first) = &parts[0];
    let expected = traits(first);
    for (file, part) in &parts[1..] {
        for ((what, ours), (_, theirs)) in expected.iter().zip(traits(part)) {
            if *ours != theirs {
                return Err(MergeError::Differ {
                    what,
                    first: (first_file.clone(), ours.clone()),
                    other: (file.clone(), theirs),
                });
            }
        }
    }
    Ok(())
}
