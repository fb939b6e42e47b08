//! Tests of the SVG plots: ticks, axes, odd data, files.

use super::*;

fn close(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-12)
}

fn balanced(svg: &str, tag: &str) -> bool {
    let open = svg.matches(&format!("<{tag} ")).count() + svg.matches(&format!("<{tag}>")).count();
    open == svg.matches(&format!("</{tag}>")).count()
}

fn band_plot() -> LinePlot {
    let t: Vec<f64> = (0..=500).map(|i| i as f64 * 0.01).collect();
    let mean: Vec<f64> = t
        .iter()
        .map(|t| (3.0 * t).sin() * (-0.3 * t).exp())
        .collect();
    let sd: Vec<f64> = t.iter().map(|t| 0.02 + 0.05 * t).collect();
    let lower = mean.iter().zip(&sd).map(|(m, s)| m - 3.0 * s).collect();
    let upper = mean.iter().zip(&sd).map(|(m, s)| m + 3.0 * s).collect();
    let mut plot = LinePlot::new("Lateral displacement q(t)", "time [s]", "q [m]");
    plot.bands
        .push(Band::new("mean ± 3σ", t.clone(), lower, upper, palette(0)));
    plot.series.push(Series::new(
        "mean (SGM)",
        t.clone(),
        mean.clone(),
        palette(0),
    ));
    plot.series.push(
        Series::new(
            "mean (LHS)",
            t,
            mean.iter().map(|m| m * 1.05).collect(),
            palette(1),
        )
        .dashed(),
    );
    plot
}

#[test]
fn ticks_are_nice_1_2_5_steps() {
    assert!(close(
        &nice_ticks(0.0, 5.0, 6),
        &[0.0, 1.0, 2.0, 3.0, 4.0, 5.0]
    ));
    assert_eq!(
        nice_ticks(0.0, 0.1, 6),
        vec![0.0, 0.02, 0.04, 0.06, 0.08, 0.1],
        "ticks should be the nearest doubles to the decimals"
    );
    assert!(close(
        &nice_ticks(-1.0, 1.0, 6),
        &[-1.0, -0.5, 0.0, 0.5, 1.0]
    ));
    assert!(close(
        &nice_ticks(0.0, 100.0, 6),
        &[0.0, 20.0, 40.0, 60.0, 80.0, 100.0]
    ));
    assert!(close(&nice_ticks(3.0, 7.0, 6), &[3.0, 4.0, 5.0, 6.0, 7.0]));
    // Reversed bounds are sorted; degenerate input does not panic.
    assert!(close(&nice_ticks(5.0, 0.0, 6), &nice_ticks(0.0, 5.0, 6)));
    assert_eq!(nice_ticks(2.0, 2.0, 6), vec![2.0]);
    assert_eq!(nice_ticks(f64::NAN, 1.0, 6), vec![1.0]);
    assert!(nice_ticks(f64::NEG_INFINITY, f64::INFINITY, 6).is_empty());
    assert_eq!(nice_ticks(0.0, 1.0, 0), vec![0.0, 1.0]);
}

#[test]
fn tick_labels_use_step_decimals_or_exponents() {
    let a = Axis::linear(0.0, 0.1);
    assert_eq!(a.labels, ["0", "0.02", "0.04", "0.06", "0.08", "0.10"]);
    let a = Axis::linear(0.0, 5e-6);
    assert_eq!(a.labels[1], "1e-6");
    let a = Axis::linear(-2.0, 2.0);
    assert!(a.labels.iter().all(|l| l != "-0"), "{:?}", a.labels);
    let a = Axis::log(Some((2e-4, 3.0)), true);
    assert_eq!(a.labels, ["0.0001", "0.001", "0.01", "0.1", "1", "10"]);
    assert_eq!((a.lo, a.hi), (1e-4, 10.0));
    let a = Axis::log(Some((1e-30, 1.0)), true);
    assert!(
        a.ticks.len() <= 9 && a.labels[0] == "1e-30",
        "{:?}",
        a.labels
    );
}

#[test]
fn band_plot_svg_is_well_formed() {
    let plot = band_plot();
    let svg = plot.to_svg();
    assert!(svg.starts_with("<svg "));
    assert!(svg.trim_end().ends_with("</svg>"));
    assert!(svg.contains("Lateral displacement q(t)"));
    assert!(svg.contains("mean ± 3σ"));
    assert!(svg.contains("time [s]") && svg.contains("q [m]"));
    assert!(balanced(&svg, "g"), "unbalanced <g>");
    assert!(balanced(&svg, "text"));
    assert!(svg.contains("stroke-dasharray"));
    assert!(svg.contains("fill-opacity=\"0.25\""));
    // Two data lines, one band, plus the tick path and two legend lines.
    assert_eq!(svg.matches("<path ").count(), 2 + 1 + 1 + 2);
    // Coordinates have at most two decimals.
    let d = svg.split("class=\"series\"").nth(1).unwrap();
    let d = &d[d.find("d=\"").unwrap() + 3..];
    let d = &d[..d.find('"').unwrap()];
    for num in d.split(|c: char| c.is_ascii_alphabetic() || c == ' ') {
        if let Some((_, frac)) = num.split_once('.') {
            assert!(frac.len() <= 2, "{num}");
        }
    }
    assert!(svg.len() < 60_000, "svg is {} bytes", svg.len());
}

#[test]
fn non_finite_points_break_the_line() {
    let mut plot = LinePlot::new("gaps", "x", "y");
    plot.series.push(Series::new(
        "s",
        vec![0.0, 1.0, 2.0, f64::NAN, 4.0, 5.0, 6.0],
        vec![0.0, 1.0, f64::INFINITY, 3.0, 4.0, f64::NAN, 6.0],
        "red",
    ));
    let svg = plot.to_svg();
    assert!(!svg.contains("NaN") && !svg.contains("inf"));
    let d = svg.split("class=\"series\"").nth(1).unwrap();
    let d = &d[d.find("d=\"").unwrap() + 3..];
    let d = &d[..d.find('"').unwrap()];
    // Runs: {0,1}, {4}, {6}.
    assert_eq!(d.matches('M').count(), 3, "{d}");
}

#[test]
fn empty_and_degenerate_plots_are_still_valid() {
    let empty = LinePlot::default().to_svg();
    assert!(empty.starts_with("<svg ") && balanced(&empty, "g"));
    let mut flat = LinePlot::new("flat", "x", "y");
    flat.series
        .push(Series::new("c", vec![1.0, 1.0], vec![2.0, 2.0], "black"));
    flat.series
        .push(Series::new("nan", vec![f64::NAN], vec![f64::NAN], "black"));
    flat.series
        .push(Series::new("short", vec![0.0, 1.0], vec![], "black"));
    let svg = flat.to_svg();
    assert!(!svg.contains("NaN") && !svg.contains("inf"));
    assert_eq!(svg.matches("<path d=\"\"").count(), 2);
    let mut log = LinePlot::new("log", "x", "y");
    log.log_y = true;
    log.series.push(Series::new(
        "s",
        vec![0.0, 1.0, 2.0],
        vec![-1.0, 0.0, 1e-3],
        "black",
    ));
    let svg = log.to_svg();
    assert!(!svg.contains("NaN") && !svg.contains("inf"));
    let huge = LinePlot {
        series: vec![Series::new(
            "h",
            vec![0.0, 1.0],
            vec![-f64::MAX, f64::MAX],
            "k",
        )],
        ..LinePlot::default()
    };
    let svg = huge.to_svg();
    assert!(!svg.contains("NaN") && !svg.contains("inf"));
}

#[test]
fn labels_are_escaped() {
    let plot = LinePlot::new("<b>&</b>", "x", "y");
    let svg = plot.to_svg();
    assert!(svg.contains("&lt;b&gt;&amp;&lt;/b&gt;"));
    assert!(!svg.contains("<b>"));
}

#[test]
fn histogram_density_integrates_to_one() {
    let samples: Vec<f64> = (0..1000).map(|i| (i as f64 * 0.7).sin()).collect();
    let (edges, dens) = histogram_density(&samples, 20);
    assert_eq!(edges.len(), 21);
    let total: f64 = dens
        .iter()
        .zip(edges.windows(2))
        .map(|(d, e)| d * (e[1] - e[0]))
        .sum();
    assert!((total - 1.0).abs() < 1e-12);
    let (edges, dens) = histogram_density(&[f64::NAN, 3.0, 3.0], 0);
    assert_eq!(edges.len(), dens.len() + 1);
    assert_eq!(edges.first(), Some(&2.5));
    assert!(histogram_density(&[f64::NAN], 5).0.is_empty());
}

#[test]
fn density_plot_has_histogram_curves_and_markers() {
    let x: Vec<f64> = (0..=200).map(|i| i as f64 * 0.02).collect();
    let pdf: Vec<f64> = x
        .iter()
        .map(|x| (-(x - 2.0f64).powi(2) / 0.5).exp() / (0.5 * std::f64::consts::PI).sqrt())
        .collect();
    let samples: Vec<f64> = (0..400).map(|i| 2.0 + (i as f64 * 0.37).sin()).collect();
    let plot = DensityPlot {
        title: "Sperling index W".into(),
        x_label: "W [-]".into(),
        curves: vec![Series::new("KDE", x, pdf, palette(0))],
        histogram: Some(histogram_density(&samples, 0)),
        markers: vec![(2.5, "limit W = 2.5".into()), (f64::NAN, "bad".into())],
    };
    let svg = plot.to_svg();
    assert!(svg.starts_with("<svg ") && balanced(&svg, "g"));
    assert!(svg.matches("<rect ").count() >= 10);
    assert!(svg.contains("limit W = 2.5"));
    assert!(svg.contains("probability density"));
    assert!(!svg.contains("NaN"));
    let empty = DensityPlot::default().to_svg();
    assert!(empty.starts_with("<svg ") && balanced(&empty, "g"));
}

#[test]
fn write_reports_the_path_on_error() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("no/such/dir/p.svg");
    let err = LinePlot::default().write(&path).unwrap_err();
    assert!(err.to_string().contains("p.svg"));
    let ok = dir.path().join("p.svg");
    band_plot().write(&ok).unwrap();
    assert!(std::fs::read_to_string(ok).unwrap().starts_with("<svg"));
}

#[test]
fn bar_chart_labels_categories_and_draws_intervals() {
    let chart = BarChart {
        title: "Sobol' indices of W".into(),
        y_label: "share of the variance [-]".into(),
        x_label: "parameter".into(),
        categories: vec!["Kpz".into(), "Cpz".into(), "Ksz".into()],
        groups: vec![
            BarGroup {
                label: "first order S".into(),
                color: palette(0).into(),
                values: vec![0.2, 0.7, f64::NAN],
                intervals: vec![Some((0.15, 0.25)), None, None],
            },
            BarGroup {
                label: "total ST".into(),
                color: palette(1).into(),
                values: vec![0.25, 0.75, 0.0],
                intervals: vec![None; 3],
            },
        ],
        y_range: Some((0.0, 1.0)),
        interval_label: "95 % interval (8 replicates, Student t)".into(),
    };
    let svg = chart.to_svg();
    assert!(svg.contains("95 % interval (8 replicates,") && svg.contains("Student t)"));
    assert!(balanced(&svg, "g") && balanced(&svg, "text"));
    for name in ["Kpz", "Cpz", "Ksz", "first order S", "total ST"] {
        assert!(svg.contains(&format!(">{name}</text>")), "{name}");
    }
    // Five bars (the NaN has none) and one error bar.
    assert_eq!(
        svg.split("class=\"bars\"")
            .nth(1)
            .unwrap()
            .split("</g>")
            .next()
            .unwrap()
            .matches("<rect ")
            .count(),
        5
    );
    assert!(!svg.contains("NaN"));
    // Many long names are slanted instead of overlapping.
    let many = BarChart {
        categories: (0..12).map(|i| format!("parameter_{i}")).collect(),
        ..chart.clone()
    };
    assert!(many.to_svg().contains("rotate(-35"));
}

#[test]
fn legends_wrap_long_labels_and_grow_the_image() {
    let long = "kernel density of 20000 draws of the chaos surrogate, which is a long label";
    let mut plot = LinePlot::new("t", "x", "y");
    plot.series.push(Series::new(
        long,
        vec![0.0, 1.0],
        vec![0.0, 1.0],
        palette(0),
    ));
    let svg = plot.to_svg();
    // Every word is there (nothing cut), on more than one line.
    assert!(
        svg.contains(">kernel density of 20000 draws of</text>"),
        "{svg}"
    );
    assert!(svg.contains("long label</text>"));
    assert!(!svg.contains('…'));
    let many = LinePlot {
        series: (0..40)
            .map(|i| {
                Series::new(
                    format!("series {i}"),
                    vec![0.0, 1.0],
                    vec![0.0, i as f64],
                    palette(i),
                )
            })
            .collect(),
        ..LinePlot::new("t", "x", "y")
    };
    let svg = many.to_svg();
    let h: f64 = svg
        .split("height=\"")
        .nth(1)
        .unwrap()
        .split('"')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(h > 40.0 * 21.0, "{h}: the legend must fit");
}

#[test]
fn density_markers_beyond_the_data_are_arrows_not_a_squashed_plot() {
    let x: Vec<f64> = (0..=100).map(|i| 2.0 + i as f64 * 0.005).collect();
    let pdf: Vec<f64> = x
        .iter()
        .map(|x| (-(x - 2.25f64).powi(2) / 0.01).exp())
        .collect();
    let plot = DensityPlot {
        title: "W".into(),
        x_label: "W [-]".into(),
        curves: vec![Series::new("KDE", x, pdf, palette(0))],
        histogram: None,
        markers: vec![(2.4, "limit 2.4".into()), (3.0, "limit 3".into())],
    };
    let svg = plot.to_svg();
    // (The legend wraps the label.)
    assert!(
        svg.contains(">limit 3 (right of the plotted</text>"),
        "{svg}"
    );
    assert!(svg.contains(">range →)</text>"), "{svg}");
    assert!(svg.contains(">limit 2.4</text>"));
    // The axis ends at the data (2.5), not at the far limit.
    assert!(svg.contains(">2.5</text>") && !svg.contains(">3.0</text>"));
}

/// Eight limits get eight colours (the palette wrapped after three), and a limit
/// beyond the plotted range has an arrow glyph in the legend, not a dashed line.
#[test]
fn limit_markers_have_their_own_colours_and_arrow_glyphs() {
    let x: Vec<f64> = (0..=100).map(|i| i as f64 * 0.01).collect();
    let pdf = vec![1.0; x.len()];
    let limits = [-1.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 2.0];
    let plot = DensityPlot {
        title: "t".into(),
        x_label: "a [m/s2]".into(),
        curves: vec![Series::new("KDE", x, pdf, palette(0))],
        histogram: None,
        markers: limits.iter().map(|&l| (l, format!("limit {l}"))).collect(),
    };
    let svg = plot.to_svg();
    let colours: std::collections::BTreeSet<&str> = (0..limits.len()).map(marker_color).collect();
    assert_eq!(colours.len(), limits.len());
    assert!(!colours.contains(palette(0)) && !colours.contains(HISTOGRAM_COLOR));
    // Legend: the six limits inside are dashed lines; the two outside are arrows (a path
    // with a filled head), in their colours.
    let legend = &svg[svg.find("<g class=\"legend\">").unwrap()..];
    assert_eq!(legend.matches("stroke-dasharray").count(), 6, "{legend}");
    for i in [0, 7] {
        let c = marker_color(i);
        assert!(
            legend.contains(&format!("stroke=\"{c}\" fill=\"{c}\"")),
            "no arrow glyph of limit {i}: {legend}"
        );
    }
    // The density axis in the inverse unit.
    assert!(svg.contains("probability density [s2/m]"), "{svg}");
}

#[test]
fn density_axis_labels_carry_the_inverse_unit() {
    assert_eq!(density_label("q [m]"), "probability density [1/m]");
    assert_eq!(density_label("W [-]"), "probability density [-]");
    assert_eq!(density_label("v_cr [m/s]"), "probability density [s/m]");
    assert_eq!(density_label("x"), "probability density");
}

/// Legend swatches are drawn with the opacity of what they stand for.
#[test]
fn legend_swatches_match_bars_and_bands() {
    let chart = BarChart {
        title: "t".into(),
        categories: vec!["a".into()],
        groups: vec![BarGroup {
            label: "S".into(),
            color: palette(0).into(),
            values: vec![0.5],
            intervals: vec![None],
        }],
        ..BarChart::default()
    };
    let svg = chart.to_svg();
    let legend = &svg[svg.find("<g class=\"legend\">").unwrap()..];
    assert!(
        legend.contains(&format!("fill-opacity=\"{BAR_OPACITY}\"")),
        "{legend}"
    );
    let mut plot = band_plot();
    plot.bands[0].opacity = 0.75;
    let svg = plot.to_svg();
    let legend = &svg[svg.find("<g class=\"legend\">").unwrap()..];
    assert!(legend.contains("fill-opacity=\"0.75\""), "{legend}");
}

/// An axis of orders has whole-number ticks only, and dots mark every point.
#[test]
fn integer_axis_and_markers() {
    let axis = Axis::integers(Some((1.0, 2.0)));
    assert_eq!(axis.ticks, vec![1.0, 2.0]);
    assert_eq!(axis.labels, vec!["1", "2"]);
    assert!(axis.lo < 1.0 && axis.hi > 2.0);
    let many = Axis::integers(Some((0.0, 60.0)));
    assert!(many.ticks.iter().all(|t| t.fract() == 0.0) && many.ticks.len() <= 21);
    let plot = LinePlot {
        series: vec![
            Series::new("s", vec![1.0, 2.0, 3.0], vec![1.0, 0.1, 0.01], palette(0)).with_markers(),
        ],
        log_y: true,
        integer_x: true,
        ..LinePlot::new("t", "order", "Std")
    };
    let svg = plot.to_svg();
    // Three points and the legend's dot.
    assert_eq!(svg.matches("<circle").count(), 4);
    assert!(svg.contains(">2</text>") && !svg.contains(">1.5</text>"));
}
