//! Each state's contribution to a field-route fit (`identifier::state_contributions`): a
//! 2-node case computed by hand, the sums over a cruciform's frames, the nodes outside every
//! virtual field's support, and what an equibiaxial node cannot tell.

use identifier::field_layout::ArmLayout;
use identifier::field_route::{FieldRoute, FieldRouteConfig, FrameOutcome};
use identifier::field_stress::Mat2;
use identifier::models::Model;
use identifier::section_cut::FieldGrid;
use identifier::state_contributions::{
    state_contributions, states_csv, ContributionError, FrameStates, STATES_CSV_HEADER,
};
use identifier::virtual_work::{EquationInput, Equations, WeightedNode};

const THICKNESS_MM: f64 = 2.0;

fn node(col: usize, gradient: Mat2, weight_mm2: Mat2) -> WeightedNode {
    WeightedNode::measured((col, 0), gradient, weight_mm2)
}

/// One frame of `cols` x 1 nodes, 1 mm apart, whose one equation weighs `nodes`.
fn one_equation(nodes: &[WeightedNode], cols: usize) -> (FieldGrid, Equations) {
    let mut gradients = vec![None; cols];
    for n in nodes {
        gradients[n.at.0] = Some(n.gradient);
    }
    let grid = FieldGrid {
        cols,
        rows: 1,
        x0_mm: 0.0,
        y0_mm: 0.0,
        step_mm: 1.0,
        gradients,
    };
    let equations = Equations::compile(&[EquationInput {
        frame: 0,
        nodes,
        thickness_mm: THICKNESS_MM,
        measured_n: 10.0,
    }])
    .unwrap();
    (grid, equations)
}

fn close(a: f64, b: f64, tolerance: f64) -> bool {
    (a - b).abs() <= tolerance * b.abs().max(1e-300)
}

/// Two nodes along x of one section cut (∇u* = w e_x ⊗ e_x), F diagonal: K1 = e_x ⊗ e_x / λ1,
/// so node n moves the equation by h w_n / λ1n ∂σ1/∂θ. Mooney-Rivlin: σ1 = 2 C10 (λ1² − λ3²)
/// − 2 C01 (λ1⁻² − λ3⁻²), whatever C10 and C01.
#[test]
fn a_two_node_cut_gives_the_hand_computed_shares() {
    let uniaxial = 1.5_f64;
    let (l2_u, equibiaxial) = (1.0 / uniaxial.sqrt(), 1.2_f64);
    let (w_u, w_e) = (2.0, 1.0);
    let nodes = [
        node(0, [[uniaxial, 0.0], [0.0, l2_u]], [[w_u, 0.0], [0.0, 0.0]]),
        node(
            1,
            [[equibiaxial, 0.0], [0.0, equibiaxial]],
            [[w_e, 0.0], [0.0, 0.0]],
        ),
    ];
    let (grid, equations) = one_equation(&nodes, 2);
    let frames = [FrameStates {
        frame_id: 7,
        grid: &grid,
        equations: &equations,
    }];
    let got = state_contributions(&Model::Mooney, &[0.3, 0.05], &frames).unwrap();
    // By hand.
    let sensitivity = |l1: f64, l2: f64, w: f64| {
        let l3 = 1.0 / (l1 * l2);
        let lever = THICKNESS_MM * w / l1;
        [
            (lever * 2.0 * (l1 * l1 - l3 * l3)).abs(),
            (lever * 2.0 * (l1.powi(-2) - l3.powi(-2))).abs(),
        ]
    };
    let s_u = sensitivity(uniaxial, l2_u, w_u);
    let s_e = sensitivity(equibiaxial, equibiaxial, w_e);
    let share_u = [s_u[0] / (s_u[0] + s_e[0]), s_u[1] / (s_u[1] + s_e[1])];
    let contribution_u = 0.5 * (share_u[0] + share_u[1]);
    assert_eq!(got.parameters, ["C10", "C01"]);
    assert_eq!(got.states.len(), 2);
    let (u, e) = (&got.states[0], &got.states[1]);
    assert_eq!((u.frame_id, u.at, u.filled), (7, (0, 0), false));
    assert!(
        close(u.contribution, contribution_u, 1e-8),
        "{u:?} vs {contribution_u}"
    );
    assert!(close(e.contribution, 1.0 - contribution_u, 1e-8), "{e:?}");
    for k in 0..2 {
        assert!(close(u.shares[k], share_u[k], 1e-8), "{u:?} vs {share_u:?}");
    }
    assert!(close(u.stretches[0], uniaxial, 1e-12) && close(u.stretches[1], l2_u, 1e-12));
    assert_eq!(e.position_mm, [1.0, 0.0]);
    // The numbers, worked out once: 0.5 (0.7257 + 0.5505) for the uniaxial node.
    assert!((contribution_u - 0.6381).abs() < 1e-4, "{contribution_u}");
    // The CSV: a row per state, the shares by parameter.
    let csv = states_csv(&got);
    let mut lines = csv.lines();
    assert_eq!(
        lines.next().unwrap(),
        format!("{STATES_CSV_HEADER},share_C10,share_C01")
    );
    let first: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(&first[..3], ["7", "0", "0"]);
    assert!(close(first[8].parse().unwrap(), contribution_u, 1e-8));
    assert_eq!(lines.count(), 1);
}

/// An equibiaxial node (F = λ I) has an isotropic nominal stress for every law, P = (s/λ) I:
/// where a virtual field only shears (∇u* off-diagonal: the tapered ramp's r w' term, the
/// force across the band), it cannot tell any parameter, and contributes exactly 0, while a
/// uniaxial state turned 30° under the same shear does. A node at rest (a rotation: every
/// law's stress is 0) contributes nothing either.
#[test]
fn an_equibiaxial_node_tells_no_parameter_through_a_shear() {
    let shear = [[0.0, 5.0], [0.0, 0.0]];
    let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
    let (a, b) = (1.4, 1.0 / 1.4f64.sqrt());
    // F = R diag(a, b) Rᵀ: a uniaxial stretch along 30°.
    let turned = [
        [a * c * c + b * s * s, (a - b) * c * s],
        [(a - b) * c * s, a * s * s + b * c * c],
    ];
    let (rc, rs) = (20f64.to_radians().cos(), 20f64.to_radians().sin());
    let nodes = [
        node(0, [[1.3, 0.0], [0.0, 1.3]], shear),
        node(1, turned, shear),
        node(2, [[rc, -rs], [rs, rc]], [[3.0, 0.0], [0.0, 0.0]]),
    ];
    let (grid, equations) = one_equation(&nodes, 3);
    let frames = [FrameStates {
        frame_id: 1,
        grid: &grid,
        equations: &equations,
    }];
    for (model, p) in [
        (Model::Mooney, vec![0.3, 0.05]),
        (Model::Ogden(2), vec![0.6, -0.1, 2.0, -2.0]),
        (Model::Gent, vec![0.7, 30.0]),
    ] {
        let got = state_contributions(&model, &p, &frames).unwrap();
        let [equi, uni, rest] = [0, 1, 2].map(|k| &got.states[k]);
        assert!(equi.shares.iter().all(|&s| s == 0.0), "{model}: {equi:?}");
        assert!(rest.contribution < 1e-9, "{model}: {rest:?}");
        assert!((uni.contribution - 1.0).abs() < 1e-9, "{model}: {uni:?}");
        assert!(uni.shares.iter().all(|&s| (s - 1.0).abs() < 1e-9));
    }
}

/// The default cruciform's layout over a field of ±80 mm whose stretch varies from the centre
/// (equibiaxial) out along the arms: the route's kept frames, every virtual field compiled.
fn route_frames() -> FieldRoute {
    let n = 65;
    let mut route = FieldRoute::new(FieldRouteConfig {
        layout: ArmLayout {
            arm_width_mm: 100.0,
            fillet_radius_mm: 20.0,
        },
        thickness_mm: THICKNESS_MM,
        models: vec![Model::Mooney],
        min_level_increment: 0.01,
        max_frames: 8,
        min_frames_to_fit: 2,
        central_ramps: true,
    });
    for (k, level) in [0.1, 0.2, 0.3].into_iter().enumerate() {
        let gradients = (0..n * n)
            .map(|i| {
                let (x, y) = (-80.0 + 2.5 * (i % n) as f64, -80.0 + 2.5 * (i / n) as f64);
                let (rx, ry) = (x.abs() / 80.0, y.abs() / 80.0);
                Some([
                    [1.0 + level * (1.0 + 0.5 * rx), 0.02 * level * rx * ry],
                    [0.0, 1.0 + level * (1.0 + 0.5 * ry)],
                ])
            })
            .collect();
        let grid = FieldGrid {
            cols: n,
            rows: n,
            x0_mm: -80.0,
            y0_mm: -80.0,
            step_mm: 2.5,
            gradients,
        };
        let outcome = route
            .push(k as u64, Some(grid), Some([100.0; 4]), level, &|_| true)
            .unwrap();
        assert_eq!(outcome, FrameOutcome::Kept);
    }
    route
}

/// Over all frames the contributions, and each parameter's shares, sum to 1; every measured
/// node is a state; a node outside every virtual field's support (the view's corners, beyond
/// every taper) contributes exactly 0.
#[test]
fn over_a_cruciforms_frames_they_sum_to_one_and_nodes_outside_every_field_give_nothing() {
    let route = route_frames();
    let frames = FrameStates::of_route(&route);
    for (model, p) in [
        (Model::Mooney, vec![0.3, 0.05]),
        (Model::Gent, vec![0.7, 30.0]),
    ] {
        let got = state_contributions(&model, &p, &frames).unwrap();
        assert_eq!(got.states.len(), 3 * 65 * 65, "{model}");
        let total: f64 = got.states.iter().map(|s| s.contribution).sum();
        assert!((total - 1.0).abs() < 1e-12, "{model}: {total}");
        for k in 0..p.len() {
            let shares: f64 = got.states.iter().map(|s| s.shares[k]).sum();
            assert!((shares - 1.0).abs() < 1e-12, "{model} {k}: {shares}");
        }
        for frame in route.frames() {
            let weighed: Vec<(usize, usize)> =
                frame.equations.origins().iter().map(|o| o.at).collect();
            let corner = (0, 0);
            assert!(
                !weighed.contains(&corner),
                "the corner is outside every field"
            );
            let state = got
                .states
                .iter()
                .find(|s| s.frame_id == frame.frame_id && s.at == corner)
                .unwrap();
            assert_eq!(state.contribution, 0.0);
            // Every node the fields weigh moves some equation here (none is at rest).
            let unweighed = got
                .states
                .iter()
                .filter(|s| s.frame_id == frame.frame_id && s.contribution == 0.0)
                .count();
            assert!(unweighed >= 65 * 65 - weighed.len(), "{unweighed}");
        }
    }
    // A model's parameters, counted; no frames: no sensitivity to share.
    assert!(matches!(
        state_contributions(&Model::Mooney, &[0.3], &frames),
        Err(ContributionError::Parameters { expected: 2, .. })
    ));
    assert!(matches!(
        state_contributions(&Model::Mooney, &[0.3, 0.05], &[]),
        Err(ContributionError::Insensitive { .. })
    ));
}
