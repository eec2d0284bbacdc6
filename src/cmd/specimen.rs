//! `dicstream specimen`: the specimen as a finite-element structure, solved offline for a path
//! of grip stretches. Geometry and law are the run configuration's `[specimen]` keys.
//!
//! Writes into `--out DIR` (created; refused if it holds anything): per converged state
//! `state_NNN.csv` (one row per node) and `state_NNN.vtk` (the T6 mesh with the nodal fields),
//! and `summary.json` (mesh, law, grip forces and solver figures per state, why it stopped).
//! Every file is written atomically.

use super::named_arg::named;
use anyhow::{bail, Context, Result};
use live::RunConfig;
use membrane::path::{solve_path, Path as SolvedPath, PathReport};
use membrane::{GripStretch, Membrane, NewtonSettings, SpecimenShape, Wrinkling};
use std::path::{Path, PathBuf};

#[derive(clap::Args, Debug)]
pub struct SpecimenArgs {
    /// Run configuration (TOML): the law (`[specimen] law_f, law_g`) and the geometry
    /// (`[specimen.geometry]`); the defaults without it (see `run --print-config`).
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// The shape, in place of the configuration's: cruciform, uniaxial_strip or
    /// plane_strain_strip.
    #[arg(long, value_parser = named::<SpecimenShape>())]
    pub shape: Option<SpecimenShape>,
    /// Nominal grip stretch (grip-to-grip distance, deformed over reference) of both axes of a
    /// cruciform, or along x of a strip.
    #[arg(long, default_value_t = 1.5)]
    pub stretch: f64,
    /// The grip stretch along x, in place of --stretch.
    #[arg(long)]
    pub stretch_x: Option<f64>,
    /// The grip stretch along y (a cruciform only), in place of --stretch.
    #[arg(long)]
    pub stretch_y: Option<f64>,
    /// States solved and written, evenly spaced from rest to the stretch (the last one at it).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub states: u32,
    /// Results folder (created; must be empty or absent).
    #[arg(long, default_value = "specimen")]
    pub out: PathBuf,
    /// Print summary.json alone on stdout (nothing else there).
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: SpecimenArgs) -> Result<()> {
    let config = RunConfig::read(args.config.as_deref())?;
    let mut choice = config.specimen.geometry.clone();
    if let Some(shape) = args.shape {
        choice.shape = shape;
    }
    let target = target_stretch(&args, choice.shape)?;
    let law = material::InvariantLaw::exp_poly(&config.specimen.law_f, &config.specimen.law_g)
        .context("[specimen] law_f, law_g")?;
    let specimen = choice
        .mesh()
        .with_context(|| format!("[specimen.geometry] {} refused", choice.shape))?;
    let membrane = Membrane::new(
        &specimen.mesh,
        specimen.thickness_mm,
        &law,
        Wrinkling::default(),
    )
    .with_context(|| format!("[specimen.geometry] {} refused", choice.shape))?;
    prepare_out(&args.out)?;
    let states = args.states as usize;
    let path = solve_path(
        &membrane,
        &specimen,
        target,
        states,
        NewtonSettings::default(),
    );
    for state in &path.states {
        write_state(&args.out, &specimen.mesh, state, choice.shape)?;
    }
    let report = PathReport {
        shape: choice.shape,
        geometry: choice.chosen(),
        law_f: &config.specimen.law_f,
        law_g: &config.specimen.law_g,
        nodes: specimen.mesh.nodes_mm.len(),
        elements: specimen.mesh.elements.len(),
        dofs: specimen.mesh.dof_count(),
        free_dofs: path.states.first().map(|s| s.equilibrium.free_dofs),
        target_grip_stretch: target,
        states_requested: states,
        states: path.states.iter().map(|s| &s.figures).collect(),
        stopped: path.stopped.as_ref().map(ToString::to_string),
    };
    let json = serde_json::to_string_pretty(&report).expect("the report serialises");
    wire::files::write_atomic(&args.out.join("summary.json"), json.as_bytes())?;
    if args.json {
        println!("{json}");
    } else {
        print_table(&path, &args.out);
    }
    match &path.stopped {
        Some(stop) => bail!(
            "the path stopped after {} of {states} states: {stop} (summary.json keeps the converged states)",
            path.states.len()
        ),
        None => Ok(()),
    }
}

/// The grip stretch asked: --stretch on every axis the shape pulls, or the axis' own flag.
fn target_stretch(args: &SpecimenArgs, shape: SpecimenShape) -> Result<GripStretch> {
    let y_default = if shape == SpecimenShape::Cruciform {
        args.stretch
    } else {
        1.0
    };
    let target = GripStretch {
        x: args.stretch_x.unwrap_or(args.stretch),
        y: args.stretch_y.unwrap_or(y_default),
    };
    Ok(target.check(shape)?)
}

/// Creates `out`, refusing one that holds anything (results of different paths never mix).
fn prepare_out(out: &Path) -> Result<()> {
    std::fs::create_dir_all(out).with_context(|| format!("--out {}", out.display()))?;
    let mut entries = std::fs::read_dir(out).with_context(|| format!("--out {}", out.display()))?;
    if let Some(entry) = entries.next() {
        let name = entry?.file_name();
        bail!(
            "--out {} is not empty (it holds {}): name a new folder, or remove it",
            out.display(),
            name.to_string_lossy()
        );
    }
    Ok(())
}

fn write_state(
    out: &Path,
    mesh: &membrane::Mesh,
    state: &membrane::PathState,
    shape: SpecimenShape,
) -> Result<()> {
    let f = &state.figures;
    let stem = format!("state_{:03}", f.state);
    let csv = membrane::output::nodes_csv(&state.nodes);
    wire::files::write_atomic(&out.join(format!("{stem}.csv")), csv.as_bytes())?;
    let title = format!(
        "dicstream specimen: {shape} at grip stretch x {}, y {}",
        f.grip_stretch.x, f.grip_stretch.y
    );
    let vtk = membrane::output::state_vtk(mesh, &state.nodes, &title);
    wire::files::write_atomic(&out.join(format!("{stem}.vtk")), vtk.as_bytes())?;
    Ok(())
}

/// One line per state on stdout: stretch, each grip's axial force, the solver's effort.
fn print_table(path: &SolvedPath, out: &Path) {
    for s in path.states.iter().map(|s| &s.figures) {
        let forces: Vec<String> = s
            .grip_axial_force_n
            .iter()
            .map(|(grip, force)| format!("{grip} {force:.2} N"))
            .collect();
        println!(
            "state {}: grip stretch x {:.4} y {:.4}; {}; λ {:.4}..{:.4}; {} load steps, {} Newton iterations, last residual {:.2e} N; {:.0} ms",
            s.state,
            s.grip_stretch.x,
            s.grip_stretch.y,
            forces.join(", "),
            s.stretch_min,
            s.stretch_max,
            s.load_steps,
            s.newton_iterations,
            s.last_step_residuals_n.last().copied().unwrap_or(0.0),
            s.solve_ms
        );
    }
    println!("results in {}", out.display());
}
