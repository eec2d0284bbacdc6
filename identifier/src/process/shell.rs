//! `Identifier`, the identifier process as it runs: the online identification, its journal,
//! the counters and the last fits. The ports stay in `run` (the WaitSet's guards borrow them):
//! each wake-up hands them to `take_samples`, and accepted points to `refit`.

use super::{
    build_report, field_sample, final_json, rig_sample, ProcessConfig, ProcessError, ProcessSummary,
};
use crate::fit::Fit;
use crate::journal::{JournalPoint, JournalWriter};
use crate::online::{FieldOutcome, FieldSample, OnlineIdentifier};
use std::time::{Duration, Instant};
use wire::identification::ReportRoute;
use wire::pubsub::{SliceSubscriber, ValuePublisher, ValueSubscriber};
use wire::{FieldHeader, FieldNode, IdentificationReport, RigState};

pub(super) struct Identifier<'c> {
    config: &'c ProcessConfig,
    /// The field route, when `config.routes` runs it.
    field: Option<super::field::FieldShell>,
    online: OnlineIdentifier,
    journal: Option<JournalWriter>,
    summary: ProcessSummary,
    last_fits: Vec<Fit>,
    last_json_write: Option<Instant>,
    last_activity: Instant,
}

impl<'c> Identifier<'c> {
    /// The online identification, its load path rebuilt from the journal when there is one.
    pub fn open(config: &'c ProcessConfig) -> Result<Self, ProcessError> {
        let mut online = OnlineIdentifier::new(config.online.clone());
        let journal = match &config.journal {
            Some(path) => {
                let restored = crate::journal::read(path)?;
                let kept = restored.iter().filter(|p| online.restore(p.state)).count();
                if !restored.is_empty() {
                    eprintln!(
                        "identifier: rebuilt the load path from {}: {kept} of {} points",
                        path.display(),
                        restored.len()
                    );
                }
                Some(JournalWriter::open(path)?)
            }
            None => None,
        };
        let field = if config.routes.runs(ReportRoute::Field) {
            let settings = config.field.as_ref().ok_or(ProcessError::NoFieldSettings {
                routes: config.routes,
            })?;
            if journal.is_some() {
                eprintln!(
                    "identifier: the field route journals nothing: after a restart it refits \
                     from the fields it receives from then on"
                );
            }
            Some(super::field::FieldShell::new(
                settings,
                &config.online.models,
            )?)
        } else {
            None
        };
        Ok(Self {
            config,
            field,
            online,
            journal,
            summary: ProcessSummary::default(),
            last_fits: Vec::new(),
            last_json_write: None,
            last_activity: Instant::now(),
        })
    }

    /// Every waiting rig sample, then every waiting field (fields name rig samples); whether
    /// a point was accepted.
    pub fn take_samples(
        &mut self,
        rig: &ValueSubscriber<RigState>,
        fields: &SliceSubscriber<FieldNode, FieldHeader>,
    ) -> Result<bool, ProcessError> {
        let mut accepted = false;
        while let Some(state) = rig.receive()? {
            self.summary.rig_samples_received += 1;
            if let Some(field) = self.field.as_mut() {
                field.on_rig(&state);
            }
            for (field, outcome) in self.online.push_rig(rig_sample(&state)) {
                accepted |= self.record(&field, outcome)?;
            }
        }
        while let Some(sample) = fields.receive()? {
            self.summary.fields_received += 1;
            if self.summary.fields_received == 1 {
                eprintln!(
                    "{} (frame {})",
                    super::FIRST_FIELD_LINE,
                    sample.user_header().frame_id
                );
            }
            if let Some(route) = self.field.as_mut() {
                route.on_field(sample.user_header(), sample.payload());
            }
            if !self.config.routes.runs(ReportRoute::Gauge) {
                continue;
            }
            if let Some(field) = field_sample(sample.user_header()) {
                let outcome = self.online.push_field(field);
                accepted |= self.record(&field, outcome)?;
            }
        }
        Ok(accepted)
    }

    /// An accepted point goes to the journal; whether it was accepted.
    fn record(
        &mut self,
        field: &FieldSample,
        outcome: FieldOutcome,
    ) -> Result<bool, wire::files::FileError> {
        let FieldOutcome::Accepted { state, .. } = outcome else {
            return Ok(false);
        };
        if let Some(journal) = self.journal.as_mut() {
            journal.append(&JournalPoint {
                state,
                frame_id: field.frame_id,
            })?;
        }
        Ok(true)
    }

    /// After accepted points: the fits published, and written at most once a second.
    pub fn refit(
        &mut self,
        publisher: &ValuePublisher<IdentificationReport>,
    ) -> Result<(), ProcessError> {
        self.last_activity = Instant::now();
        let Some(fits) = self.online.refit() else {
            return Ok(());
        };
        let mut report = build_report(&fits, self.online.point_counts(), self.online.last_accepted);
        report.t_published_ns = wire::monotonic_ns();
        publisher.publish(report)?;
        self.summary.reports_published += 1;
        self.last_fits = fits;
        if self
            .last_json_write
            .is_none_or(|t| t.elapsed() >= Duration::from_secs(1))
        {
            self.write_json()?;
            self.last_json_write = Some(Instant::now());
        }
        Ok(())
    }

    /// The field route's refit when it is due (new frames, a second since the last), published
    /// and written.
    pub fn refit_field(
        &mut self,
        publisher: &ValuePublisher<IdentificationReport>,
    ) -> Result<(), ProcessError> {
        if let Some(report) = self.field.as_mut().and_then(|f| f.refit(false)) {
            self.last_activity = Instant::now();
            publisher.publish(report)?;
            self.summary.reports_published += 1;
            self.write_json()?;
        }
        Ok(())
    }

    /// `max_fields` received, or idle for the idle timeout.
    pub fn limit_reached(&self) -> bool {
        let config = self.config;
        config
            .max_fields
            .is_some_and(|m| self.summary.fields_received >= m)
            || config
                .idle_timeout
                .is_some_and(|t| self.last_activity.elapsed() > t)
    }

    /// The last fits written (those of the restored path when nothing new came), and the
    /// summary.
    pub fn finish(mut self) -> Result<ProcessSummary, ProcessError> {
        if let Some(field) = self.field.as_mut() {
            // The last frames' fit, written below (the publisher is gone at the end).
            let _ = field.refit(true);
        }
        if self.last_fits.is_empty() {
            // Restored points and nothing new: still report the fits of the path.
            self.last_fits = self.online.refit().unwrap_or_default();
        }
        self.summary.best_model = self.last_fits.first().map(|f| f.model.name());
        self.write_json()?;
        if let (Some(path), Some(field)) = (&self.config.states_csv, &self.field) {
            match field.states_csv() {
                Some(Ok(csv)) => wire::files::write_atomic(path, csv.as_bytes())?,
                Some(Err(e)) => eprintln!("identifier: {} not written: {e}", path.display()),
                None => {}
            }
        }
        self.summary.points = self.online.point_counts();
        Ok(self.summary)
    }

    fn write_json(&self) -> Result<(), ProcessError> {
        wire::files::write_atomic(
            &self.config.output_json,
            final_json(
                &self.summary,
                &self.online,
                &self.last_fits,
                self.field.as_ref().map(|f| f.json()),
            )?
            .as_bytes(),
        )?;
        Ok(())
    }
}
