//! The settings of a link process, typed: what `dicstream run` writes for the link it starts
//! (`dicstream link --settings FILE`), and what `dicstream link --config` makes from a run's
//! configuration and its flags.

use crate::config::LinkSection;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LinkSettings {
    /// The instance, the same on both hosts.
    pub instance: String,
    /// `[link]` as written (checked into a plan at start).
    pub link: LinkSection,
    /// Where the link keeps its counts (`crate::counts::LinkCounts`) as it goes, resumed from
    /// when it starts again; `dicstream run` reads them for its verdict.
    #[serde(default)]
    pub counts_json: Option<PathBuf>,
}
