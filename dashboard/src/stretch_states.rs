//! The states the latest field reached in the (λ1, λ2) plane (paper Fig. 5; pure): a point
//! per valid node, its in-plane principal stretches λ1 ≥ λ2 from its strains (a Seth-Hill
//! measure's principal values give the stretches: log λ = exp e, Green λ = √(1 + 2e),
//! nominal λ = 1 + e; small strain carries no rotation, so its nodes use their gradient),
//! evenly subsampled to at most [`MAX_POINTS`].

use crate::series::significant;
use serde_json::{json, Value};
use wire::{FieldNode, NodeStatus, StrainMeasure};

/// Points sent at most (every k-th valid node beyond).
pub const MAX_POINTS: usize = 2000;

/// λ1 ≥ λ2 of one node, None when it is not `ok` or its values are not finite.
pub fn node_stretches(n: &FieldNode, measure: StrainMeasure) -> Option<[f64; 2]> {
    if n.status != NodeStatus::Ok as u32 {
        return None;
    }
    let (exx, eyy, exy) = (f64::from(n.exx), f64::from(n.eyy), f64::from(n.exy));
    let mean = 0.5 * (exx + eyy);
    let radius = (0.5 * (exx - eyy)).hypot(exy);
    let stretch = |e: f64| principal_stretch(measure, e);
    let stretches = match measure {
        StrainMeasure::Small => {
            let f = [
                [1.0 + f64::from(n.du_dx), f64::from(n.du_dy)],
                [f64::from(n.dv_dx), 1.0 + f64::from(n.dv_dy)],
            ];
            identifier::field_stress::principal_stretches(&f)
        }
        _ => stretch(mean + radius)
            .zip(stretch(mean - radius))
            .map(|(a, b)| [a, b]),
    }?;
    stretches
        .iter()
        .all(|l| l.is_finite() && *l > 0.0)
        .then_some(stretches)
}

/// The stretch λ of a principal strain `e` in a Seth-Hill measure (None for small strain,
/// which carries no rotation, or outside the measure's domain).
pub fn principal_stretch(measure: StrainMeasure, e: f64) -> Option<f64> {
    let stretch = match measure {
        StrainMeasure::Log => e.exp(),
        StrainMeasure::Green => (1.0 + 2.0 * e).sqrt(),
        StrainMeasure::Nominal => 1.0 + e,
        StrainMeasure::Small => return None,
    };
    (stretch.is_finite() && stretch > 0.0).then_some(stretch)
}

/// The principal strain of a stretch `stretch` in a Seth-Hill measure (None for small strain).
pub fn principal_strain(measure: StrainMeasure, stretch: f64) -> Option<f64> {
    match measure {
        StrainMeasure::Log => Some(stretch.ln()),
        StrainMeasure::Green => Some(0.5 * (stretch * stretch - 1.0)),
        StrainMeasure::Nominal => Some(stretch - 1.0),
        StrainMeasure::Small => None,
    }
}

/// A strain `[exx, eyy, exy]` in measure `from` expressed in measure `to`: the same principal
/// axes, each principal strain through its stretch. None when either measure is small strain
/// (and not the same) or the strain is outside `from`'s domain. The page's map of another
/// measure converts its node values the same way (`app.js`, `convertStrain`).
pub fn convert_strain(e: [f64; 3], from: StrainMeasure, to: StrainMeasure) -> Option<[f64; 3]> {
    if from == to {
        return Some(e);
    }
    let [exx, eyy, exy] = e;
    let mean = 0.5 * (exx + eyy);
    let radius = (0.5 * (exx - eyy)).hypot(exy);
    let theta = 0.5 * (2.0 * exy).atan2(exx - eyy);
    let (s, c) = theta.sin_cos();
    let principal = |e: f64| principal_strain(to, principal_stretch(from, e)?);
    let (a, b) = (principal(mean + radius)?, principal(mean - radius)?);
    let converted = [
        a * c * c + b * s * s,
        a * s * s + b * c * c,
        (a - b) * c * s,
    ];
    converted.iter().all(|v| v.is_finite()).then_some(converted)
}

/// `{"l1": [..], "l2": [..], "valid": n, "shown": k}` for the nodes of one field.
pub fn json(nodes: &[FieldNode], measure: StrainMeasure) -> Value {
    let states: Vec<[f64; 2]> = nodes
        .iter()
        .filter_map(|n| node_stretches(n, measure))
        .collect();
    let shown = states.len().min(MAX_POINTS);
    let kept: Vec<[f64; 2]> = (0..shown)
        .map(|i| states[i * states.len() / shown])
        .collect();
    json!({
        "l1": kept.iter().map(|s| significant(s[0], 5)).collect::<Vec<_>>(),
        "l2": kept.iter().map(|s| significant(s[1], 5)).collect::<Vec<_>>(),
        "valid": states.len(),
        "shown": shown,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn node(exx: f64, eyy: f64, exy: f64) -> FieldNode {
        FieldNode {
            exx: exx as f32,
            eyy: eyy as f32,
            exy: exy as f32,
            status: NodeStatus::Ok as u32,
            ..FieldNode::default()
        }
    }

    #[test]
    fn stretches_are_the_exponentials_of_the_principal_log_strains() {
        // Uniaxial λ = 1.3 rotated by 30°: ln λ along (cos, sin), −ln λ / 2 across.
        let (a, b, t) = (1.3f64.ln(), -0.5 * 1.3f64.ln(), 30f64.to_radians());
        let (c, s) = (t.cos(), t.sin());
        let n = node(
            a * c * c + b * s * s,
            a * s * s + b * c * c,
            (a - b) * c * s,
        );
        let [l1, l2] = node_stretches(&n, StrainMeasure::Log).unwrap();
        assert!((l1 - 1.3).abs() < 1e-6 && (l2 - 1.3f64.powf(-0.5)).abs() < 1e-6);
        // Green-Lagrange (λ² − 1)/2 and nominal λ − 1 give the same stretches.
        let g = node(
            0.5 * (1.2f64.powi(2) - 1.0),
            0.5 * (1.1f64.powi(2) - 1.0),
            0.0,
        );
        let [l1, l2] = node_stretches(&g, StrainMeasure::Green).unwrap();
        assert!((l1 - 1.2).abs() < 1e-6 && (l2 - 1.1).abs() < 1e-6);
        let [l1, l2] = node_stretches(&node(0.1, 0.2, 0.0), StrainMeasure::Nominal).unwrap();
        assert!((l1 - 1.2).abs() < 1e-6 && (l2 - 1.1).abs() < 1e-6);
        // Small strain: from the gradient.
        let mut m = node(0.0, 0.0, 0.0);
        m.du_dx = 0.25;
        let [l1, l2] = node_stretches(&m, StrainMeasure::Small).unwrap();
        assert!((l1 - 1.25).abs() < 1e-6 && (l2 - 1.0).abs() < 1e-6);
        // Refused nodes have no state.
        let mut bad = node(0.1, 0.1, 0.0);
        bad.status = NodeStatus::LowZncc as u32;
        assert!(node_stretches(&bad, StrainMeasure::Log).is_none());
    }

    #[test]
    fn a_strain_converts_between_measures_on_its_principal_axes() {
        // Uniaxial λ = 1.3 rotated by 30°, in log strain, expressed in Green-Lagrange.
        let t = 30f64.to_radians();
        let (c, s) = (t.cos(), t.sin());
        let tensor = |a: f64, b: f64| {
            [
                a * c * c + b * s * s,
                a * s * s + b * c * c,
                (a - b) * c * s,
            ]
        };
        let (l1, l2) = (1.3f64, 1.3f64.powf(-0.5));
        let log = tensor(l1.ln(), l2.ln());
        let green = tensor(0.5 * (l1 * l1 - 1.0), 0.5 * (l2 * l2 - 1.0));
        let converted = convert_strain(log, StrainMeasure::Log, StrainMeasure::Green).unwrap();
        for k in 0..3 {
            assert!(
                (converted[k] - green[k]).abs() < 1e-12,
                "{converted:?} vs {green:?}"
            );
        }
        // And back, through nominal.
        let nominal = convert_strain(green, StrainMeasure::Green, StrainMeasure::Nominal).unwrap();
        let back = convert_strain(nominal, StrainMeasure::Nominal, StrainMeasure::Log).unwrap();
        for k in 0..3 {
            assert!((back[k] - log[k]).abs() < 1e-12, "{back:?} vs {log:?}");
        }
        // Small strain converts to nothing; a Green strain below -1/2 has no stretch.
        assert!(convert_strain(log, StrainMeasure::Small, StrainMeasure::Log).is_none());
        assert!(convert_strain(log, StrainMeasure::Log, StrainMeasure::Small).is_none());
        let impossible = [-0.6, 0.0, 0.0];
        assert!(convert_strain(impossible, StrainMeasure::Green, StrainMeasure::Log).is_none());
    }

    #[test]
    fn a_large_field_is_subsampled_evenly_to_the_cap() {
        let nodes: Vec<FieldNode> = (0..5000).map(|i| node(1e-4 * i as f64, 0.0, 0.0)).collect();
        let j = json(&nodes, StrainMeasure::Log);
        assert_eq!(j["valid"], 5000);
        assert_eq!(j["shown"], MAX_POINTS);
        let l1 = j["l1"].as_array().unwrap();
        assert_eq!(l1.len(), MAX_POINTS);
        // Spread over the whole field: first and last nodes' ranges both present.
        assert!((l1[0].as_f64().unwrap() - 1.0).abs() < 1e-9);
        assert!(l1[MAX_POINTS - 1].as_f64().unwrap() > 1.6);
        assert_eq!(json(&[], StrainMeasure::Log)["shown"], 0);
    }
}
