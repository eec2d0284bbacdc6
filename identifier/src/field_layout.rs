//! Where the field route's virtual fields go (issue 25, section 4.c on line): from the
//! cruciform's geometry and the measured grid's extent, a band across each arm's straight part
//! within the field of view (the section cut, its edges handled as the tapered ramp handles the
//! specimen's outline) and a ramp through the centre for each arm (the equibiaxial states), each
//! with the grip whose force it balances. An arm the view does not cross whole gets no field;
//! a view that crosses no arm is an error, never an empty fit.

use crate::section_cut::{ArmAxis, FieldGrid};
use crate::tapered_ramp::TaperedRamp;

/// The cruciform as the field route needs it (mm, reference configuration, centred on 0): the
/// numbers of `membrane`'s `CruciformGeometry` (the process copies them from it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ArmLayout {
    /// The arms' width (and the central square's side).
    pub arm_width_mm: f64,
    /// Fillet radius at the re-entrant corners: the arms are straight from half their width
    /// plus this radius on.
    pub fillet_radius_mm: f64,
}

/// The grips of a cruciform in `rig/state`'s actuator order (X+, X−, Y+, Y−).
pub const GRIPS: [&str; 4] = ["x+", "x-", "y+", "y-"];

/// One virtual field and the grip (index in [`GRIPS`]) whose force it balances.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlacedField {
    pub ramp: TaperedRamp,
    pub grip: usize,
    /// A band across the arm's straight part (a section cut) rather than through the centre.
    pub is_cut: bool,
}

/// Why no virtual field fits the view.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum LayoutError {
    #[error(
        "the field of view (x {x_mm:?} mm, y {y_mm:?} mm) crosses no arm of the cruciform whole \
         (arms {width_mm} mm wide, straight from {straight_mm} mm): the field route needs a \
         band across at least one arm (widen the view: [camera] mm_per_px)"
    )]
    NoArmInView {
        x_mm: [f64; 2],
        y_mm: [f64; 2],
        width_mm: f64,
        straight_mm: f64,
    },
}

/// Longest section-cut band along an arm, mm.
const CUT_LENGTH_MM: f64 = 8.0;

/// The extent of the grid's node squares along x and along y, mm.
fn extent(grid: &FieldGrid) -> ([f64; 2], [f64; 2]) {
    let s = grid.step_mm;
    let span = |origin: f64, n: usize| {
        [
            origin - 0.5 * s,
            origin + (n.max(1) - 1) as f64 * s + 0.5 * s,
        ]
    };
    (span(grid.x0_mm, grid.cols), span(grid.y0_mm, grid.rows))
}

/// The virtual fields of `layout` that `grid`'s view holds: per arm crossed whole, a cut
/// across its straight part as far out as the view allows, and a ramp through the centre
/// tapered to zero one node step inside the view's edge across (where the other arms leave
/// it); a ramp whose taper has no room is left out.
///
/// The central ramp's taper starts beyond the fillets (at the other arms' straight part)
/// wherever the view leaves two steps for it there: then u* is constant along the fillets and
/// ∇u* vanishes in the edge band the correlator loses where the stresses are highest; the
/// taper crosses only straight arm edges, whose lost band is nearly the state beside it.
/// Measured when written (`tests/suite/field_resolution.rs`, noise-free, the live test's ±92
/// mm view): Mooney-Rivlin's equibiaxial gap 1.5 % → 0.56 % with the edge's nodes lost, 1.7 %
/// → 0.74 % with ZOI gradients. A narrower view tapers from the central square's edge.
pub fn place_fields(layout: &ArmLayout, grid: &FieldGrid) -> Result<Vec<PlacedField>, LayoutError> {
    let (x_mm, y_mm) = extent(grid);
    let s = grid.step_mm;
    let half_width = 0.5 * layout.arm_width_mm;
    let straight = half_width + layout.fillet_radius_mm;
    let mut fields = vec![];
    for (grip, name) in GRIPS.iter().enumerate() {
        let (axis, along, across) = match name.as_bytes()[0] {
            b'x' => (ArmAxis::X, x_mm, y_mm),
            _ => (ArmAxis::Y, y_mm, x_mm),
        };
        let mirrored = name.ends_with('-');
        // The view's reach along the arm, outward (mirrored on the − side), one step inside.
        let reach = if mirrored { -along[0] } else { along[1] } - s;
        // Across: the view must hold the arm's whole width and one more step.
        let room_across = (-across[0]).min(across[1]) - s;
        if room_across < half_width + s {
            continue;
        }
        let to_mm = reach.min(straight + CUT_LENGTH_MM);
        if to_mm - straight >= s {
            fields.push(PlacedField {
                ramp: TaperedRamp {
                    axis,
                    from_mm: to_mm - (to_mm - straight).min(CUT_LENGTH_MM),
                    to_mm,
                    centre_mm: 0.0,
                    flat_half_width_mm: half_width,
                    zero_half_width_mm: half_width + s,
                    mirrored,
                },
                grip,
                is_cut: true,
            });
        }
        // Through the centre: r over the middle fifth of the square, w to zero before the view
        // loses the other arms, from beyond the fillets where the view has room.
        let band = 0.2 * half_width;
        let flat = if room_across > straight + 2.0 * s {
            straight
        } else {
            half_width
        };
        if room_across > half_width + 2.0 * s && reach > band {
            fields.push(PlacedField {
                ramp: TaperedRamp {
                    axis,
                    from_mm: -band,
                    to_mm: band,
                    centre_mm: 0.0,
                    flat_half_width_mm: flat,
                    zero_half_width_mm: room_across,
                    mirrored,
                },
                grip,
                is_cut: false,
            });
        }
    }
    if !fields.iter().any(|f| f.is_cut) {
        return Err(LayoutError::NoArmInView {
            x_mm,
            y_mm,
            width_mm: 2.0 * half_width,
            straight_mm: straight,
        });
    }
    Ok(fields)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The default cruciform: 100 mm arms, 20 mm fillets.
    fn layout() -> ArmLayout {
        ArmLayout {
            arm_width_mm: 100.0,
            fillet_radius_mm: 20.0,
        }
    }

    fn grid(half_mm: f64, step_mm: f64) -> FieldGrid {
        let n = (2.0 * half_mm / step_mm).round() as usize + 1;
        FieldGrid {
            cols: n,
            rows: n,
            x0_mm: -half_mm,
            y0_mm: -half_mm,
            step_mm,
            gradients: vec![None; n * n],
        }
    }

    #[test]
    fn a_wide_view_gets_a_cut_and_a_central_ramp_per_arm() {
        let fields = place_fields(&layout(), &grid(79.0, 2.5)).unwrap();
        assert_eq!(fields.iter().filter(|f| f.is_cut).count(), 4);
        assert_eq!(fields.len(), 8);
        for f in fields.iter().filter(|f| f.is_cut) {
            // Beyond the fillets, inside the view.
            assert!(f.ramp.from_mm >= 70.0 && f.ramp.to_mm <= 79.0, "{f:?}");
            assert!(f.ramp.to_mm - f.ramp.from_mm >= 2.5);
        }
        let x_minus = fields.iter().find(|f| f.is_cut && f.grip == 1).unwrap();
        assert!(x_minus.ramp.mirrored && x_minus.ramp.axis == ArmAxis::X);
    }

    #[test]
    fn the_central_ramps_taper_clears_the_fillets_where_the_view_has_room() {
        let central = |half_mm: f64| -> Vec<TaperedRamp> {
            let fields = place_fields(&layout(), &grid(half_mm, 5.0)).unwrap();
            fields
                .iter()
                .filter(|f| !f.is_cut)
                .map(|f| f.ramp)
                .collect()
        };
        // ±92 mm: w = 1 up to the other arms' straight part (70 mm), 0 a step inside the view.
        let wide = central(92.0);
        assert_eq!(wide.len(), 4);
        for ramp in &wide {
            assert_eq!(ramp.flat_half_width_mm, 70.0, "{ramp:?}");
            assert!(ramp.zero_half_width_mm > 70.0 + 2.0 * 5.0, "{ramp:?}");
        }
        // ±80 mm: too little room beyond the fillets; the taper starts at the square's edge.
        for ramp in central(80.0) {
            assert_eq!(ramp.flat_half_width_mm, 50.0, "{ramp:?}");
        }
    }

    #[test]
    fn a_view_that_crosses_no_arm_is_refused() {
        // The paper's 2 mm gauge view: nothing but the centre.
        let error = place_fields(&layout(), &grid(1.9, 0.24)).unwrap_err();
        assert!(error.to_string().contains("crosses no arm"), "{error}");
        // Wide enough across, but short of the straight part.
        assert!(place_fields(&layout(), &grid(65.0, 2.5)).is_err());
    }
}
