//! What a run is asked to run: everything, or the checks a `--scenario` or
//! `--requirement` names, or a shard's share of them (`--shard K/N`). Both
//! sides and every suite select the same way.

use serde::{Deserialize, Serialize};

/// Everything, or the checks whose name contains one of `scenarios` or that
/// exercise one of `requirements`; of those, a shard's share.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Selection {
    pub scenarios: Vec<String>,
    pub requirements: Vec<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shard: Option<Shard>,
}

/// Shard `index` of `count` (1-based, as `--shard 2/4` writes it): a
/// deterministic share of a run's (profile, check) pairs, the same on every
/// machine, so that the shards of a campaign together run each check once.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    pub index: u32,
    pub count: u32,
}

impl Shard {
    /// `K/N` with 1 ≤ K ≤ N.
    pub fn parse(text: &str) -> Result<Self, String> {
        let (k, n) = text
            .split_once('/')
            .ok_or_else(|| format!("`{text}` is not K/N (a shard K of N, such as 2/4)"))?;
        let number = |part: &str, what: &str| {
            part.trim()
                .parse::<u32>()
                .map_err(|_| format!("`{text}`: {what} `{part}` is not a whole number"))
        };
        let (index, count) = (number(k, "K")?, number(n, "N")?);
        if count == 0 || index == 0 || index > count {
            return Err(format!(
                "`{text}`: shards count from 1 to N, and N is at least 1"
            ));
        }
        Ok(Shard { index, count })
    }

    /// Does this shard take the check `name` of `profile`? FNV-1a over both:
    /// stable across machines, platforms and canif builds.
    pub fn takes(&self, profile: &str, name: &str) -> bool {
        let mut hash: u64 = 0xcbf2_9ce4_8422_2325;
        for byte in profile.bytes().chain([0]).chain(name.bytes()) {
            hash = (hash ^ u64::from(byte)).wrapping_mul(0x0100_0000_01b3);
        }
        hash % u64::from(self.count) == u64::from(self.index - 1)
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl Selection {
    pub fn is_everything(&self) -> bool {
        self.scenarios.is_empty() && self.requirements.is_empty() && self.shard.is_none()
    }

    /// Does the selection take the check `name` of `profile` that exercises `covers`?
    pub fn admits<'a>(
        &self,
        profile: &str,
        name: &str,
        mut covers: impl Iterator<Item = &'a str>,
    ) -> bool {
        let named = self.scenarios.is_empty() && self.requirements.is_empty()
            || self.scenarios.iter().any(|s| name.contains(s.as_str()))
            || covers.any(|id| self.requirements.iter().any(|r| r == id));
        named && self.shard.is_none_or(|shard| shard.takes(profile, name))
    }

    /// The same selection on every shard: what a campaign as a whole runs.
    pub fn unsharded(&self) -> Selection {
        Selection {
            shard: None,
            ..self.clone()
        }
    }

    /// The options that made it: `--scenario X --requirement Y --shard K/N`.
    pub fn flags(&self) -> String {
        let scenarios = self.scenarios.iter().map(|s| format!("--scenario {s}"));
        let requirements = self
            .requirements
            .iter()
            .map(|r| format!("--requirement {r}"));
        let shard = self.shard.iter().map(|s| format!("--shard {s}"));
        scenarios
            .chain(requirements)
            .chain(shard)
            .collect::<Vec<_>>()
            .join(" ")
    }

    /// Why a requirement it leaves out was not run.
    pub fn not_run(&self) -> crate::verdict::NotRunReason {
        if self.is_everything() {
            crate::verdict::NotRunReason::NotSelected
        } else {
            crate::verdict::NotRunReason::Selection(self.flags())
        }
    }

    /// [`Selection::not_run`] in words.
    pub fn describe(&self) -> String {
        self.not_run().to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_selection_admits_by_name_part_or_by_requirement() {
        let selection = Selection {
            scenarios: vec!["tx-batches".into()],
            requirements: vec!["HS-RX-001".into()],
            shard: None,
        };
        assert!(selection.admits("p", "tx-batches [11-bit]", std::iter::empty()));
        assert!(selection.admits("p", "rx-handshake", ["HS-RX-001"].into_iter()));
        assert!(!selection.admits("p", "rx-handshake", ["HS-RX-002"].into_iter()));
        assert_eq!(
            selection.describe(),
            "left out by the selection (--scenario tx-batches --requirement HS-RX-001)"
        );
        assert_eq!(
            Selection::default().describe(),
            "no check of this run reached it (nothing was left out by a selection)"
        );
        assert!(Selection::default().admits("p", "anything", std::iter::empty()));
    }

    #[test]
    fn the_shards_of_a_run_take_each_check_exactly_once() {
        let checks: Vec<(String, String)> = (0..400)
            .map(|n| (format!("profile-{}", n % 5), format!("check {n}")))
            .collect();
        for count in 1..=7 {
            let shards: Vec<Selection> = (1..=count)
                .map(|index| Selection {
                    shard: Some(Shard { index, count }),
                    ..Selection::default()
                })
                .collect();
            for (profile, name) in &checks {
                let takers = shards
                    .iter()
                    .filter(|s| s.admits(profile, name, std::iter::empty()))
                    .count();
                assert_eq!(takers, 1, "{profile} {name} in {count} shards");
            }
            // No shard of a few is left empty by the hash.
            if count <= 4 {
                for shard in &shards {
                    let taken = checks
                        .iter()
                        .filter(|(p, n)| shard.admits(p, n, std::iter::empty()))
                        .count();
                    assert!(taken > 400 / count as usize / 2, "{shard:?} takes {taken}");
                }
            }
        }
    }

    #[test]
    fn a_shard_is_k_of_n_and_nothing_else() {
        assert_eq!(Shard::parse("2/4"), Ok(Shard { index: 2, count: 4 }));
        for bad in ["0/4", "5/4", "1/0", "2", "a/4", "2/b", "-1/4", ""] {
            assert!(Shard::parse(bad).is_err(), "{bad}");
        }
        let selection = Selection {
            shard: Some(Shard { index: 2, count: 4 }),
            ..Selection::default()
        };
        assert!(!selection.is_everything());
        assert_eq!(selection.flags(), "--shard 2/4");
        assert!(selection.unsharded().is_everything());
    }
}
