//! What a reference renewal costs the frames around it in one trial of `bench pipeline`, from
//! `frames.csv` (one row per field): for the renewing frame (the one a later field names as its
//! reference), each of the three fields after it, and the other fields, the medians of the
//! field's waiting (capture to the correlator taking the frame, queueing included), correlating
//! (the correlator's own time for the field, `correlate_ms`) and latency (capture to published).
//! The live correlator publishes a renewing frame's field before it renews the reference and
//! then measures the new bases against the origin a part per frame: that work is in no field's
//! correlating time, it shows as the next fields' waiting when they arrive while it runs.

use serde::Serialize;

/// Medians (ms) of the fields in one position relative to a renewal.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct FieldCostMs {
    pub fields: u64,
    pub waiting: f64,
    pub correlating: f64,
    pub latency: f64,
}

/// The renewals of one trial and the fields around them.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct RenewalCosts {
    pub renewals: u64,
    /// The renewing fields.
    pub renewing: FieldCostMs,
    /// The first, second and third field after each renewing one (not renewing themselves).
    pub after: [FieldCostMs; 3],
    /// Every other field.
    pub others: FieldCostMs,
}

impl RenewalCosts {
    /// From `frames.csv`'s text (columns `frame_id`, `reference_frame_id`, `latency_field_ms`,
    /// `correlate_ms`); all zero when a column is missing.
    pub fn of_frames_csv(text: &str) -> RenewalCosts {
        let mut lines = text.lines();
        let header: Vec<&str> = lines.next().unwrap_or("").split(',').collect();
        let column = |name: &str| header.iter().position(|c| *c == name);
        let (Some(id_at), Some(reference_at), Some(latency_at), Some(correlate_at)) = (
            column("frame_id"),
            column("reference_frame_id"),
            column("latency_field_ms"),
            column("correlate_ms"),
        ) else {
            return RenewalCosts::default();
        };
        // (frame id, reference id, latency, correlating)
        let rows: Vec<(u64, u64, f64, f64)> = lines
            .filter_map(|line| {
                let cells: Vec<&str> = line.split(',').collect();
                Some((
                    cells.get(id_at)?.parse().ok()?,
                    cells.get(reference_at)?.parse().ok()?,
                    cells.get(latency_at)?.parse().ok()?,
                    cells.get(correlate_at)?.parse().ok()?,
                ))
            })
            .collect();
        let named: std::collections::HashSet<u64> = rows.iter().map(|r| r.1).collect();
        // The origin's own field names it too, and renews nothing.
        let renewing: Vec<bool> = rows
            .iter()
            .map(|r| named.contains(&r.0) && r.1 != r.0)
            .collect();
        // Position after the last renewal: 0 renewing, 1..=3 after, 4 other.
        let mut groups: [Vec<(f64, f64)>; 5] = Default::default();
        let mut since: Option<usize> = None;
        for (row, &renews) in rows.iter().zip(&renewing) {
            since = if renews {
                Some(0)
            } else {
                since.map(|s| s + 1)
            };
            let position = since.filter(|&s| s <= 3).unwrap_or(4);
            groups[position].push((row.2, row.3));
        }
        let cost = |group: &[(f64, f64)]| -> FieldCostMs {
            if group.is_empty() {
                return FieldCostMs::default();
            }
            let median = |f: &dyn Fn(&(f64, f64)) -> f64| {
                let mut v: Vec<f64> = group.iter().map(f).collect();
                v.sort_by(f64::total_cmp);
                v[v.len() / 2]
            };
            FieldCostMs {
                fields: group.len() as u64,
                waiting: median(&|g| (g.0 - g.1).max(0.0)),
                correlating: median(&|g| g.1),
                latency: median(&|g| g.0),
            }
        };
        let [g0, g1, g2, g3, g4] = &groups;
        RenewalCosts {
            renewals: renewing.iter().filter(|&&r| r).count() as u64,
            renewing: cost(g0),
            after: [cost(g1), cost(g2), cost(g3)],
            others: cost(g4),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_renewing_field_and_the_three_after_it() {
        // Frame 2 renews (fields 3.. name it), and frame 7 (field 8 names it); the waiting is
        // the latency less the correlating.
        let csv = "frame_id,reference_frame_id,latency_field_ms,correlate_ms\n\
            0,0,30,20\n1,0,30,20\n2,0,40,25\n3,2,90,20\n4,2,60,22\n5,2,35,21\n6,2,30,20\n7,2,42,26\n8,7,80,24\n";
        let costs = RenewalCosts::of_frames_csv(csv);
        assert_eq!(costs.renewals, 2);
        assert_eq!(costs.renewing.fields, 2);
        assert_eq!(costs.renewing.correlating, 26.0);
        assert_eq!(costs.renewing.latency, 42.0);
        assert_eq!(costs.after[0].fields, 2);
        assert_eq!(costs.after[0].waiting, 70.0);
        assert_eq!(costs.after[1].fields, 1);
        assert_eq!(costs.after[1].waiting, 38.0);
        assert_eq!(costs.after[2].correlating, 21.0);
        // Fields 0, 1 (before any renewal) and 6 (the fourth after one).
        assert_eq!(costs.others.fields, 3);
        assert_eq!(costs.others.latency, 30.0);
        assert_eq!(
            RenewalCosts::of_frames_csv("x\n1\n"),
            RenewalCosts::default()
        );
    }
}
