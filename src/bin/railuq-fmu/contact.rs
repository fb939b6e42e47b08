//! `railuq-fmu contact`: computes a contact table from wheel and rail profiles, writes it in the
//! table-file format and a plot beside it (FILE.svg: Δr(y), contact angles, roll, equivalent
//! conicity).

use std::fs;
use std::path::{Path, PathBuf};
use std::time::Instant;

use railuq::contact::conicity::DeltaR;
use railuq::contact::smooth::smoothed;
use railuq::contact::{
    compute, ContactError, ContactSettings, ContactSolution, Profile, RollingCurvature,
};

use crate::svg::{render, Curve, Panel};

/// Usage of the command.
pub const USAGE: &str = "railuq-fmu contact --out FILE [--wheel CSV] [--rail CSV] [--inclination N]
       [--gauge MM] [--flange-back MM] [--r0 M] [--n0 N] [--y-max MM] [--step MM]
       [--curvature meridian|radius] [--smooth MM]";

/// Help on the options.
pub const HELP: &str =
    "contact writes the contact table of a wheelset on a track (FILE, CSV) and its plot
(FILE.svg). Defaults: S1002 wheels on UIC60 rails inclined 1:40 (--inclination 40; inf for
upright rails), gauge 1435 mm at 14 mm below the top, flange backs 1360 mm apart, r0 = 0.425 m,
N0 = the Cooperrider car's weight / 8, y from -17 to 17 mm in steps of 0.01 mm. --wheel and
--rail read measured profiles: lines `y, z` in mm; wheel y from the flange back (rolling circle
at 70 mm), rail y from its centre line; both positive toward the field side, z up. --curvature radius
takes 1/r for the wheel's curvature along the rolling direction (as RSGEO) instead of cos δ / r.
--smooth MM averages every column over a bell-shaped window of three boxes of half-width MM in y
(default 0: the rigid contact as computed, with its jumps); the Vehicle FMU's built-in table is
the default table with --smooth 0.05 (see the README, Contact geometry).";

/// Failures of the command.
#[derive(Debug, thiserror::Error)]
pub enum ContactCliError {
    /// The command line is wrong.
    #[error("{0}")]
    Usage(String),
    /// File system error on a path.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// A profile file is not a profile.
    #[error("{path}: {source}")]
    Profile {
        /// The file.
        path: PathBuf,
        /// The cause (names a line, never its text).
        source: railuq::contact::ProfileError,
    },
    /// The table cannot be computed.
    #[error(transparent)]
    Contact(#[from] ContactError),
}

/// The parsed command line.
#[derive(Debug, PartialEq)]
pub struct ContactArgs {
    out: PathBuf,
    wheel: Option<PathBuf>,
    rail: Option<PathBuf>,
    inclination: f64,
    gauge_mm: f64,
    flange_back_mm: f64,
    r0: f64,
    n0: Option<f64>,
    y_max_mm: f64,
    step_mm: f64,
    curvature: RollingCurvature,
    smooth_mm: f64,
}

/// Parses the options after `contact`.
pub fn parse(args: &[String]) -> Result<ContactArgs, ContactCliError> {
    let mut a = ContactArgs {
        out: PathBuf::new(),
        wheel: None,
        rail: None,
        inclination: 40.0,
        gauge_mm: 1435.0,
        flange_back_mm: 1360.0,
        r0: 0.425,
        n0: None,
        y_max_mm: 17.0,
        step_mm: 0.01,
        curvature: RollingCurvature::Meridian,
        smooth_mm: 0.0,
    };
    let mut out = None;
    let mut it = args.iter();
    while let Some(opt) = it.next() {
        let value = |it: &mut std::slice::Iter<String>| {
            it.next()
                .cloned()
                .ok_or_else(|| ContactCliError::Usage(format!("{opt} needs a value")))
        };
        let number = |it: &mut std::slice::Iter<String>| -> Result<f64, ContactCliError> {
            let v = value(it)?;
            v.parse::<f64>()
                .ok()
                .filter(|x| !x.is_nan())
                .ok_or_else(|| ContactCliError::Usage(format!("{opt} needs a number")))
        };
        match opt.as_str() {
            "--out" => out = Some(PathBuf::from(value(&mut it)?)),
            "--wheel" => a.wheel = Some(PathBuf::from(value(&mut it)?)),
            "--rail" => a.rail = Some(PathBuf::from(value(&mut it)?)),
            "--inclination" => a.inclination = number(&mut it)?,
            "--gauge" => a.gauge_mm = number(&mut it)?,
            "--flange-back" => a.flange_back_mm = number(&mut it)?,
            "--r0" => a.r0 = number(&mut it)?,
            "--n0" => a.n0 = Some(number(&mut it)?),
            "--y-max" => a.y_max_mm = number(&mut it)?,
            "--step" => a.step_mm = number(&mut it)?,
            "--smooth" => a.smooth_mm = number(&mut it)?,
            "--curvature" => {
                a.curvature = match value(&mut it)?.as_str() {
                    "meridian" => RollingCurvature::Meridian,
                    "radius" => RollingCurvature::Radius,
                    _ => {
                        return Err(ContactCliError::Usage(
                            "--curvature takes meridian or radius".into(),
                        ))
                    }
                }
            }
            _ => return Err(ContactCliError::Usage(format!("unknown option {opt}"))),
        }
    }
    a.out = out.ok_or_else(|| ContactCliError::Usage("--out FILE is required".into()))?;
    if !(a.smooth_mm >= 0.0 && a.smooth_mm.is_finite()) {
        return Err(ContactCliError::Usage(
            "--smooth MM (half-width of the moving average in y) needs MM >= 0".into(),
        ));
    }
    if a.inclination.is_nan() || a.inclination <= 0.0 {
        return Err(ContactCliError::Usage(
            "--inclination N (rails at 1:N) needs N > 0 (inf for upright rails)".into(),
        ));
    }
    Ok(a)
}

fn read_profile(
    path: &Path,
    parse: impl Fn(&str) -> Result<Profile, railuq::contact::ProfileError>,
) -> Result<Profile, ContactCliError> {
    let text = fs::read_to_string(path).map_err(|source| ContactCliError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse(&text).map_err(|source| ContactCliError::Profile {
        path: path.to_path_buf(),
        source,
    })
}

/// The settings of the command line.
pub fn settings(a: &ContactArgs) -> Result<ContactSettings, ContactCliError> {
    let mut s = ContactSettings::default();
    if let Some(p) = &a.wheel {
        s.wheel = read_profile(p, |t| Profile::wheel_from_csv(t, s.rolling_circle))?;
    }
    if let Some(p) = &a.rail {
        s.rail = read_profile(p, Profile::rail_from_csv)?;
    }
    s.inclination = (1.0 / a.inclination).atan();
    s.gauge = a.gauge_mm * 1e-3;
    s.flange_back = a.flange_back_mm * 1e-3;
    s.r0 = a.r0;
    if let Some(n0) = a.n0 {
        s.n0 = n0;
    }
    s.y_min = -a.y_max_mm * 1e-3;
    s.y_max = a.y_max_mm * 1e-3;
    s.y_step = a.step_mm * 1e-3;
    s.rolling_curvature = a.curvature;
    Ok(s)
}

/// Writes `bytes` to `path` by the rules of the `out-file` crate (uq-driver's): a new name, a
/// regular file or a link through a temporary file renamed over it (a link is replaced, never
/// written through); a device or FIFO written into, never replaced; `-` standard output.
pub fn write_output(path: &Path, bytes: &[u8]) -> Result<(), ContactCliError> {
    out_file::write(path, bytes).map_err(|source| ContactCliError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// The plot of a solution: Δr(y), contact angles, roll, and λ_eq over the amplitudes.
pub fn plot(s: &ContactSolution, conicity: &[(f64, f64)], title: &str) -> String {
    let every = (s.geometry.len() / 1200).max(1);
    let rows: Vec<_> = s.geometry.iter().step_by(every).collect();
    let mm = |v: f64| v * 1e3;
    let series = |f: &dyn Fn(&railuq::contact::geometry::GeometryRow) -> f64| -> Vec<(f64, f64)> {
        rows.iter().map(|g| (mm(g.y), f(g))).collect()
    };
    let panels = [
        Panel {
            title: "Rolling radius difference".into(),
            x_label: "wheelset displacement y [mm]".into(),
            y_label: "Δr = r_L − r_R [mm]".into(),
            curves: vec![Curve {
                label: "Δr".into(),
                color: "#1f77b4",
                points: series(&|g| mm(g.left.r - g.right.r)),
            }],
        },
        Panel {
            title: "Contact angles (relative to the axle)".into(),
            x_label: "wheelset displacement y [mm]".into(),
            y_label: "δ [rad]".into(),
            curves: vec![
                Curve {
                    label: "δ_L".into(),
                    color: "#1f77b4",
                    points: series(&|g| g.left.delta),
                },
                Curve {
                    label: "δ_R".into(),
                    color: "#d62728",
                    points: series(&|g| g.right.delta),
                },
            ],
        },
        Panel {
            title: "Wheelset roll".into(),
            x_label: "wheelset displacement y [mm]".into(),
            y_label: "φ [mrad]".into(),
            curves: vec![Curve {
                label: "φ".into(),
                color: "#2ca02c",
                points: series(&|g| 1e3 * g.roll),
            }],
        },
        Panel {
            title: "Equivalent conicity (EN 15302)".into(),
            x_label: "amplitude ŷ [mm]".into(),
            y_label: "λ_eq = tan γe".into(),
            curves: vec![Curve {
                label: "λ_eq".into(),
                color: "#9467bd",
                points: conicity.iter().map(|&(a, c)| (mm(a), c)).collect(),
            }],
        },
    ];
    render(title, &panels, 2)
}

/// Runs the command: computes, writes the table and its plot, prints a summary.
pub fn run(a: &ContactArgs) -> Result<(), ContactCliError> {
    let settings = settings(a)?;
    let start = Instant::now();
    let solution = compute(&settings)?;
    let elapsed = start.elapsed();
    let (y, dr): (Vec<f64>, Vec<f64>) = solution.delta_r().into_iter().unzip();
    let conicity: Vec<(f64, f64)> = match DeltaR::new(&y, &dr) {
        Ok(d) => (1..=100)
            .map(|k| k as f64 * 1e-4)
            .filter_map(|amp| d.conicity(amp).ok().map(|c| (amp, c)))
            .collect(),
        Err(_) => Vec::new(),
    };
    let table = smoothed(&solution.table, a.smooth_mm * 1e-3);
    write_output(&a.out, table.to_string().as_bytes())?;
    let mut svg_path = a.out.clone().into_os_string();
    svg_path.push(".svg");
    let svg_path = PathBuf::from(svg_path);
    let title = format!(
        "{} on {}, 1:{}, gauge {} mm, flange backs {} mm",
        if a.wheel.is_some() {
            "wheel profile"
        } else {
            "S1002"
        },
        if a.rail.is_some() {
            "rail profile"
        } else {
            "UIC60"
        },
        a.inclination,
        a.gauge_mm,
        a.flange_back_mm
    );
    write_output(&svg_path, plot(&solution, &conicity, &title).as_bytes())?;
    println!(
        "wrote {} ({} rows, computed in {:.1} ms) and {}",
        a.out.display(),
        solution.table.rows().len(),
        elapsed.as_secs_f64() * 1e3,
        svg_path.display()
    );
    match solution.flange_contact() {
        Some(y) => println!("flange contact (δ ≥ 0.5 rad) from y = {:.2} mm", y * 1e3),
        None => println!("no flange contact within the table"),
    }
    if let Some((_, c)) = conicity.iter().find(|(amp, _)| (amp - 3e-3).abs() < 1e-9) {
        println!("equivalent conicity at 3 mm amplitude: {c:.4}");
    }
    if solution.conformal_rows > 0 {
        println!(
            "{} rows nearly conformal: lateral curvature held at its floor",
            solution.conformal_rows
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(s: &str) -> Vec<String> {
        s.split_whitespace().map(str::to_owned).collect()
    }

    #[test]
    fn options_parse_with_defaults_and_errors_are_reported() {
        let a = parse(&args("--out t.csv --inclination 20 --gauge 1432")).unwrap();
        assert_eq!(a.out, PathBuf::from("t.csv"));
        let s = settings(&a).unwrap();
        assert!((s.inclination - 0.05f64.atan()).abs() < 1e-15 && s.gauge == 1.432);
        assert_eq!(s.flange_back, 1.36);
        assert!(parse(&args("--gauge 1435")).is_err());
        assert!(parse(&args("--out x --gauge")).is_err());
        assert!(parse(&args("--out x --bogus 1")).is_err());
        assert!(parse(&args("--out x --inclination 0")).is_err());
        let s = settings(&parse(&args("--out x --inclination inf")).unwrap()).unwrap();
        assert_eq!(s.inclination, 0.0);
    }

    #[test]
    fn outputs_go_through_the_shared_output_rules() {
        // The rules themselves are tested in the out-file crate; here: this command uses them
        // (a link planted as the output is replaced, not written through).
        let dir = std::env::temp_dir().join(format!("railuq-contact-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        let victim = dir.join("victim");
        fs::write(&victim, "keep").unwrap();
        let out = dir.join("t.csv");
        std::os::unix::fs::symlink(&victim, &out).unwrap();
        write_output(&out, b"new").unwrap();
        assert_eq!(fs::read_to_string(&victim).unwrap(), "keep");
        assert_eq!(fs::read_to_string(&out).unwrap(), "new");
        assert!(write_output(&dir, b"x").is_err());
        fs::remove_dir_all(&dir).unwrap();
    }
}
