//! The error of settings that cannot be used (a camera, a bake, a decomposition, shadows).

/// Settings that cannot be used, and why: `what` names the settings, `reason` the problem.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("invalid {what}: {reason}")]
pub struct InvalidSettings {
    pub what: &'static str,
    pub reason: String,
}

impl InvalidSettings {
    pub fn new(what: &'static str, reason: impl Into<String>) -> Self {
        Self {
            what,
            reason: reason.into(),
        }
    }
}
