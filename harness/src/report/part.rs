//! `shard.json`: what a shard of a campaign (`canif run --shard K/N`) keeps
//! of its run so that `canif merge` can judge all shards' checks together,
//! exactly as one run of them all would. Written beside the shard's own
//! reports; its checks are the run's, not yet judged.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::{ProfileChecks, RunMeta};
use crate::run::{Selection, Shard};
use crate::verdict::Evidence;

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
    /// has (lockstep cases first, then the Gherkin scenarios), on every shard
    /// the same: the merged checks are put back in this order.
    pub order: Vec<usize>,
    #[serde(flatten)]
    pub checks: ProfileChecks,
}

impl ProfilePart {
    /// The part of `checks`, placed by the plan's case names: `lockstep`
    /// (lockstep scenarios or node checks) and `gherkin` (the Gherkin
    /// scenarios' ids), in the plan's order.
    pub fn new(
        profile: &str,
        checks: ProfileChecks,
        lockstep: &[String],
        gherkin: &[String],
    ) -> Self {
        let place = |names: &[String], base: usize| {
            names
                .iter()
                .enumerate()
                .rev()
                .map(|(n, name)| (name.clone(), base + n))
                .collect::<BTreeMap<String, usize>>()
        };
        let lockstep_places = place(lockstep, 0);
        let gherkin_places = place(gherkin, lockstep.len());
        let unplaced = lockstep.len() + gherkin.len();
        let order = checks
            .checks
            .iter()
            .map(|check| match &check.evidence {
                Evidence::Scenario(name) | Evidence::NodeCheck(name) => {
                    lockstep_places.get(name).copied()
                }
                Evidence::Gherkin(id) => gherkin_places.get(id).copied(),
            })
            // A check the plan does not name keeps its own place after the plan's.
            .map(|place| place.unwrap_or(unplaced))
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
