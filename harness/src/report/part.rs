//! `shard.json`: what a shard of a campaign (`canif run --shard K/N`) keeps
//! of its run so that `canif merge` can judge all shards' checks together,
//! exactly as one run of them all would. Written beside the shard's own
//! reports; its checks are the run's, not yet judged.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::{ProfileChecks, RunMeta};
use crate::run::{Selection, Shard};

/// The shape of `shard.json` this canif writes and reads.
pub const PART_FORMAT: u32 = 1;

/// One shard's run, before judging.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ShardPart {
    pub format: u32,
    pub shard: Shard,
    pub meta: RunMeta,
    /// The selection the shard ran, its share included.
    pub selection: Selection,
    /// The command line's arguments but those a shard may have of its own
    /// (`--shard`, `--report`, `--jobs`, `--trace`), sorted: every shard of
    /// a campaign runs the same plan.
    pub command: Vec<String>,
    /// What the shard's run left out, line by line (its share among them).
    pub left_out: Vec<String>,
    pub interrupted: bool,
    pub flaky: Vec<String>,
    pub wall_time_ms: u64,
    pub profiles: Vec<ProfilePart>,
}

/// One profile's checks on a shard, each with its place in the plan.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ProfilePart {
    pub profile: String,
    /// For each check, its case's place among every case the profile's plan
    /// has (`canif list scenarios`' order: lockstep cases, then the Gherkin
    /// scenarios), the same on every shard: the merged checks are put back
    /// in this order.
    pub order: Vec<usize>,
    #[serde(flatten)]
    pub checks: ProfileChecks,
}

impl ProfilePart {
    /// The part of `checks`, each placed by its name among `plan`, the
    /// names of every case the profile's plan has, in order.
    pub fn new(profile: &str, checks: ProfileChecks, plan: &[String]) -> Self {
        // The first place of a name (its checks stay in their shard's order).
        let mut places: BTreeMap<&str, usize> = BTreeMap::new();
        for (place, name) in plan.iter().enumerate() {
            places.entry(name).or_insert(place);
        }
        let order = checks
            .checks
            .iter()
            // A check the plan does not name keeps its own place after the plan's.
            .map(|check| {
                places
                    .get(check.evidence.name())
                    .copied()
                    .unwrap_or(plan.len())
            })
            .collect();
        ProfilePart {
            profile: profile.to_string(),
            order,
            checks,
        }
    }
}

impl ShardPart {
    /// Reads a `shard.json`; the error names what does not fit.
    pub fn parse(text: &str) -> Result<Self, String> {
        let value: serde_json::Value =
            serde_json::from_str(text).map_err(|e| format!("not a canif shard.json: {e}"))?;
        let format = value.get("format").and_then(|f| f.as_u64());
        if format != Some(u64::from(PART_FORMAT)) {
            return Err(format!(
                "a shard.json of format {}; this canif reads format {PART_FORMAT}: run the shard again with this canif",
                format.map_or("(none)".to_string(), |f| f.to_string())
            ));
        }
        serde_json::from_value(value).map_err(|e| format!("not a canif shard.json: {e}"))
    }
}
