//! The emotion map (`emotion_map.svg`): every take as a point and every emotion's level vector,
//! in the plane of the two strongest emotion directions, and the level table of the report.
//!
//! The plane is spanned by the two leading principal axes of the emotion points (centred on
//! their mean); a one-dimensional space is drawn as a line across a lower box, titled with
//! its one direction.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use nalgebra::{DMatrix, SymmetricEigen};

use super::Report;

const W: f64 = 520.0;
const H: f64 = 420.0;
/// Height of a one-direction map (a line, no plane).
const H_LINE: f64 = 160.0;
const MARGIN: f64 = 50.0;
/// Colours of the emotions, in name order, cycling.
const PALETTE: [&str; 8] = [
    "#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2", "#17becf",
];

fn esc(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// The two axes of the plane (unit vectors over the space's dimensions) and the centre.
fn plane(points: &[Vec<f64>]) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let d = points.first().map_or(0, Vec::len);
    let n = points.len().max(1) as f64;
    let centre: Vec<f64> = (0..d)
        .map(|j| points.iter().map(|p| p[j]).sum::<f64>() / n)
        .collect();
    let cov = DMatrix::from_fn(d, d, |a, b| {
        points
            .iter()
            .map(|p| (p[a] - centre[a]) * (p[b] - centre[b]))
            .sum::<f64>()
            / n
    });
    let eig = SymmetricEigen::new(cov);
    let mut order: Vec<usize> = (0..d).collect();
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let axis = |i: usize| -> Vec<f64> {
        order
            .get(i)
            .map(|&k| eig.eigenvectors.column(k).iter().copied().collect())
            .unwrap_or_else(|| vec![0.0; d])
    };
    (axis(0), axis(1), centre)
}

fn project(p: &[f64], axis: &[f64], centre: &[f64]) -> f64 {
    p.iter()
        .zip(axis)
        .zip(centre)
        .map(|((v, a), c)| (v - c) * a)
        .sum()
}

/// Each take as (its emotion's index among `names`, its point on the map).
fn take_points(
    report: &Report,
    components: &[usize],
    names: &[&String],
    xy: &dyn Fn(&[f64]) -> (f64, f64),
) -> Vec<(usize, (f64, f64))> {
    report
        .takes
        .iter()
        .filter_map(|t| {
            let e = names.iter().position(|n| **n == t.emotion)?;
            let p: Vec<f64> = components.iter().map(|&k| t.component_means[k]).collect();
            Some((e, xy(&p)))
        })
        .collect()
}

/// The map's box and title, with the axis across it for a line.
fn map_frame(line: bool, h: f64, components: &[usize]) -> String {
    let mut svg = format!(
        r##"<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{h}" font-family="sans-serif"><rect width="100%" height="100%" fill="#fff"/><text x="{MARGIN}" y="24" font-size="14" font-weight="bold">{}</text>"##,
        map_title(line, components)
    );
    if line {
        let _ = write!(
            svg,
            r##"<line class="axis" x1="{MARGIN}" y1="{y}" x2="{}" y2="{y}" stroke="#888"/>"##,
            W - MARGIN,
            y = h / 2.0
        );
    }
    svg
}

/// The map's title: the plane of the first two directions, or the one direction's line.
fn map_title(line: bool, components: &[usize]) -> String {
    match (line, components) {
        (true, [k]) => {
            format!("Emotion map: takes and emotion levels along the one emotion direction, c{k}")
        }
        (true, _) => "Emotion map: takes and emotion levels along the one emotion direction".into(),
        (false, _) => "Emotion map: takes and emotion levels, first two emotion directions".into(),
    }
}

/// The map, or `None` when the analysis found no emotion space.
pub fn emotion_map(report: &Report) -> Option<String> {
    let space = report.space.as_ref()?;
    if space.components.is_empty() || space.points.is_empty() {
        return None;
    }
    let names: Vec<&String> = space.points.keys().collect();
    let levels: Vec<Vec<f64>> = space.points.values().map(|p| p.level.clone()).collect();
    let (ax, ay, centre) = plane(&levels);
    let xy = |p: &[f64]| (project(p, &ax, &centre), project(p, &ay, &centre));
    let takes = take_points(report, &space.components, &names, &xy);
    let all: Vec<(f64, f64)> = takes
        .iter()
        .map(|t| t.1)
        .chain(levels.iter().map(|l| xy(l)))
        .collect();
    let span = |f: fn(&(f64, f64)) -> f64| {
        let lo = all.iter().map(f).fold(f64::INFINITY, f64::min);
        let hi = all.iter().map(f).fold(f64::NEG_INFINITY, f64::max);
        (lo, (hi - lo).max(1e-9))
    };
    let ((x0, xs), (y0, ys)) = (span(|p| p.0), span(|p| p.1));
    // One direction: a line across the middle of a lower box, not an empty plane.
    let line = levels.first().map_or(0, Vec::len) < 2;
    let h = if line { H_LINE } else { H };
    let scale = ((W - 2.0 * MARGIN) / xs).min((H - 2.0 * MARGIN) / ys.max(xs * 0.05));
    let px = |x: f64| MARGIN + (x - x0) * scale;
    let py = |y: f64| match line {
        true => h / 2.0,
        false => H - MARGIN - (y - y0) * scale,
    };
    let mut svg = map_frame(line, h, &space.components);
    for (e, (x, y)) in &takes {
        let _ = write!(
            svg,
            r##"<circle class="take" cx="{:.1}" cy="{:.1}" r="3" fill="{}" fill-opacity="0.45"/>"##,
            px(*x),
            py(*y),
            PALETTE[e % PALETTE.len()]
        );
    }
    for (e, (name, level)) in names.iter().zip(&levels).enumerate() {
        let (x, y) = xy(level);
        let _ = write!(
            svg,
            r##"<circle class="emotion" data-emotion="{n}" cx="{:.1}" cy="{:.1}" r="7" fill="{c}" stroke="#000"/><text x="{:.1}" y="{:.1}" font-size="13">{n}</text>"##,
            px(x),
            py(y),
            px(x) + 10.0,
            py(y) - 8.0,
            n = esc(name),
            c = PALETTE[e % PALETTE.len()]
        );
    }
    svg.push_str("</svg>\n");
    Some(svg)
}

/// The level table (rows: emotions; columns: emotion components, with spreads) and the notes
/// on emotions that cannot be told apart, as HTML.
pub fn level_table(report: &Report) -> String {
    let Some(space) = report.space.as_ref().filter(|s| !s.components.is_empty()) else {
        return String::new();
    };
    let mut html = String::from("<table><tr><th>emotion</th><th>takes</th>");
    for k in &space.components {
        let _ = write!(html, "<th>c{k}</th>");
    }
    html.push_str("</tr>");
    for (name, p) in &space.points {
        let _ = write!(html, "<tr><td>{}</td><td>{}</td>", esc(name), p.takes);
        for (l, s) in p.level.iter().zip(&p.spread) {
            let _ = write!(html, "<td>{l:+.3} ± {s:.3}</td>");
        }
        html.push_str("</tr>");
    }
    html.push_str("</table>");
    let close: BTreeMap<(&str, &str), (f64, f64)> = space
        .indistinct
        .iter()
        .map(|i| ((i.a.as_str(), i.b.as_str()), (i.distance, i.spread)))
        .collect();
    for ((a, b), (d, s)) in close {
        let _ = write!(
            html,
            "<p class=\"indistinct\"><b>{} and {} cannot be told apart</b>: their levels are {d:.3} apart, against a spread of {s:.3} across takes.</p>",
            esc(a),
            esc(b)
        );
    }
    html
}
