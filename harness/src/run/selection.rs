//! What a run is asked to run: everything, or the checks a `--scenario` or
//! `--requirement` names. Both sides and every suite select the same way.

/// Everything, or the checks whose name contains one of `scenarios` or that
/// exercise one of `requirements`.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Selection {
    pub scenarios: Vec<String>,
    pub requirements: Vec<String>,
}

impl Selection {
    pub fn is_everything(&self) -> bool {
        self.scenarios.is_empty() && self.requirements.is_empty()
    }

    /// Does the selection take a check of this name that exercises `covers`?
    pub fn admits<'a>(&self, name: &str, mut covers: impl Iterator<Item = &'a str>) -> bool {
        self.is_everything()
            || self.scenarios.iter().any(|s| name.contains(s.as_str()))
            || covers.any(|id| self.requirements.iter().any(|r| r == id))
    }

    /// The options that made it: `--scenario X --requirement Y`.
    pub fn flags(&self) -> String {
        let scenarios = self.scenarios.iter().map(|s| format!("--scenario {s}"));
        let requirements = self
            .requirements
            .iter()
            .map(|r| format!("--requirement {r}"));
        scenarios.chain(requirements).collect::<Vec<_>>().join(" ")
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
        };
        assert!(selection.admits("tx-batches [11-bit]", std::iter::empty()));
        assert!(selection.admits("rx-handshake", ["HS-RX-001"].into_iter()));
        assert!(!selection.admits("rx-handshake", ["HS-RX-002"].into_iter()));
        assert_eq!(
            selection.describe(),
            "left out by the selection (--scenario tx-batches --requirement HS-RX-001)"
        );
        assert_eq!(
            Selection::default().describe(),
            "no check of this run reached it (nothing was left out by a selection)"
        );
        assert!(Selection::default().admits("anything", std::iter::empty()));
    }
}
