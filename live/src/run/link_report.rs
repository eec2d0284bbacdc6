//! What the link the run started (`[link] start_with_run`) carried and lost, read back from the
//! counts it kept (`link_counts.json`, written by the link every second and at its exit, and
//! gone on from by a link started again): `summary.json`'s `link`, a line at the run's end, and
//! a doubt in its verdict when the link lost anything.

use crate::config::RunConfig;
use crate::results::ResultsDir;
use serde::Serialize;

#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct LinkReport {
    /// The link's counts as it last wrote them; None when it wrote none (it never opened its
    /// session, or was killed at once), which the verdict says.
    pub counts: Option<link::LinkCounts>,
    /// Ids lost by the link coming in (fields, frames, rig states, reports): gaps beyond what
    /// the sender declared it skipped on purpose.
    pub lost: u64,
    /// The counts file could not be read, and why.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub unreadable: Option<String>,
}

impl LinkReport {
    /// The report of the run's link; None when the run started none.
    pub fn of(config: &RunConfig, results: &ResultsDir) -> Option<LinkReport> {
        if !config.link_started_by_run() {
            return None;
        }
        let path = results.link_counts_json();
        let (counts, unreadable) = match std::fs::read_to_string(&path) {
            Ok(text) => match link::LinkCounts::parse(&text) {
                Ok(counts) => (Some(counts), None),
                Err(e) => (None, Some(format!("{}: {e}", path.display()))),
            },
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => (None, None),
            Err(e) => (None, Some(format!("{}: {e}", path.display()))),
        };
        Some(LinkReport {
            lost: counts.as_ref().map_or(0, link::LinkCounts::lost),
            counts,
            unreadable,
        })
    }

    /// What makes the run doubtful, if anything: what the link lost, or its counts missing.
    pub fn doubt(&self) -> Option<String> {
        match &self.counts {
            None => Some(format!(
                "what the link lost is unknown: it left no counts ({})",
                self.unreadable
                    .as_deref()
                    .unwrap_or("no link_counts.json; logs/link.log says why")
            )),
            Some(counts) => counts.lost_text().map(|lost| {
                format!(
                    "the link to the other host lost {lost} (gaps beyond what the sender \
                     declared skipped; logs/link.log names them)"
                )
            }),
        }
    }

    /// The run's last line about the link.
    pub fn line(&self) -> String {
        let Some(counts) = &self.counts else {
            return "link: no counts (logs/link.log)".to_string();
        };
        let out = counts
            .out
            .iter()
            .map(|(service, c)| format!("{service} out: {} sent", c.sent));
        let into = counts
            .into
            .iter()
            .map(|(service, c)| format!("{service} in: {} received, {} lost", c.received, c.lost));
        let carried = out.chain(into).collect::<Vec<_>>().join("; ");
        match counts.lost_text() {
            None => format!("link: nothing lost ({carried})"),
            Some(lost) => format!("link: LOST {lost} on the link ({carried})"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn report(counts: Option<link::LinkCounts>) -> LinkReport {
        LinkReport {
            lost: counts.as_ref().map_or(0, link::LinkCounts::lost),
            counts,
            unreadable: None,
        }
    }

    #[test]
    fn a_link_that_lost_fields_makes_the_run_doubtful_and_says_so() {
        let mut counts = link::LinkCounts::new("lab");
        counts.set_out(
            link::LinkedService::RigState,
            link::OutCounts {
                sent: 2400,
                ..Default::default()
            },
        );
        counts.set_in(
            link::LinkedService::Fields,
            link::InCounts {
                received: 190,
                lost: 50,
                ..Default::default()
            },
        );
        let lossy = report(Some(counts.clone()));
        assert_eq!(
            lossy.line(),
            "link: LOST 50 fields on the link (rig/state out: 2400 sent; fields in: 190 \
             received, 50 lost)"
        );
        assert!(lossy
            .doubt()
            .unwrap()
            .starts_with("the link to the other host lost 50 fields"));
        counts.set_in(link::LinkedService::Fields, link::InCounts::default());
        let whole = report(Some(counts));
        assert_eq!(whole.doubt(), None);
        assert!(whole.line().starts_with("link: nothing lost"));
        assert!(report(None).doubt().unwrap().contains("left no counts"));
    }
}
