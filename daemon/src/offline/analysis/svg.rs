//! Hand-written SVG charts (no plotting dependency): the method's Figure 1 (four bar charts) and
//! Figure 2 (component series over alternating-emotion takes).

use std::fmt::Write as _;

use ica_core::model::Role;

use super::Report;

const BAR_W: f64 = 360.0;
const BAR_H: f64 = 220.0;
const MARGIN: f64 = 40.0;

/// Fill colour of a role, shared by both charts and the HTML legend.
pub fn role_colour(role: Role) -> &'static str {
    match role {
        Role::Emotion => "#d62728",
        Role::Speech => "#1f77b4",
        Role::Eyebrows => "#2ca02c",
        Role::Eyelids => "#9467bd",
        Role::Other | Role::Unknown => "#7f7f7f",
    }
}

fn esc(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// One bar chart panel at (x0, y0): a value per component, bars coloured by role.
fn panel(svg: &mut String, x0: f64, y0: f64, title: &str, values: &[f64], roles: &[Role]) {
    let max = values.iter().fold(0.0f64, |a, v| a.max(v.abs())).max(1e-12);
    let n = values.len().max(1) as f64;
    let plot_w = BAR_W - 2.0 * MARGIN;
    let plot_h = BAR_H - 2.0 * MARGIN;
    let base = y0 + MARGIN + plot_h;
    let _ = write!(
        svg,
        r##"<g><text x="{:.1}" y="{:.1}" font-size="14" font-weight="bold">{}</text>"##,
        x0 + MARGIN,
        y0 + 24.0,
        esc(title)
    );
    let _ = write!(
        svg,
        r##"<line x1="{:.1}" y1="{base:.1}" x2="{:.1}" y2="{base:.1}" stroke="#000"/>"##,
        x0 + MARGIN,
        x0 + MARGIN + plot_w
    );
    let _ = write!(
        svg,
        r##"<text x="{:.1}" y="{:.1}" font-size="10" text-anchor="end">{max:.3}</text>"##,
        x0 + MARGIN - 4.0,
        y0 + MARGIN + 4.0
    );
    let slot = plot_w / n;
    for (k, (&v, &role)) in values.iter().zip(roles).enumerate() {
        let h = v.abs() / max * plot_h;
        let x = x0 + MARGIN + k as f64 * slot + slot * 0.15;
        let _ = write!(
            svg,
            r##"<rect class="bar" data-component="{k}" data-value="{v:.6}" x="{x:.1}" y="{:.1}" width="{:.1}" height="{h:.1}" fill="{}"><title>c{k}: {v:.4} ({role:?})</title></rect>"##,
            base - h,
            slot * 0.7,
            role_colour(role)
        );
        let _ = write!(
            svg,
            r##"<text x="{:.1}" y="{:.1}" font-size="10" text-anchor="middle">{k}</text>"##,
            x + slot * 0.35,
            base + 14.0
        );
    }
    svg.push_str("</g>");
}

/// Figure 1: `d_emotion`, `|d_mouth|`, `|d_eyebrows|`, `|d_eyelids|` per component.
pub fn components_chart(report: &Report) -> String {
    let roles: Vec<Role> = report.components.iter().map(|c| c.role).collect();
    let metric = |name: &str| -> Vec<f64> {
        report
            .components
            .iter()
            .map(|c| c.d_region.get(name).copied().unwrap_or(0.0).abs())
            .collect()
    };
    let emotion: Vec<f64> = report
        .components
        .iter()
        .map(|c| c.d_emotion.unwrap_or(0.0))
        .collect();
    let emotion_title = if report.emotion_measured {
        "(a) emotion: d_emotion"
    } else {
        "(a) emotion: not measured (no pairs)"
    };
    let panels = [
        (emotion_title, emotion),
        ("(b) speech: |d_mouth|", metric("mouth")),
        ("(c) eyebrows: |d_eyebrows|", metric("eyebrows")),
        ("(d) eyelids: |d_eyelids|", metric("eyelids")),
    ];
    let mut svg = format!(
        r##"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="sans-serif"><rect width="100%" height="100%" fill="#fff"/>"##,
        w = 2.0 * BAR_W,
        h = 2.0 * BAR_H + 20.0
    );
    for (i, (title, values)) in panels.iter().enumerate() {
        let (col, row) = ((i % 2) as f64, (i / 2) as f64);
        panel(&mut svg, col * BAR_W, row * BAR_H, title, values, &roles);
    }
    let _ = write!(
        svg,
        r##"<text x="10" y="{:.1}" font-size="11">horizontal: component index; bar colour: role (red emotion, blue speech, green eyebrows, purple eyelids, grey other)</text>"##,
        2.0 * BAR_H + 12.0
    );
    svg.push_str("</svg>");
    svg
}

/// One take the timeline draws: its sentence, emotion and components (frames x m).
#[derive(Debug, Clone)]
pub struct TimelineTake {
    /// Sentence id.
    pub sentence: String,
    /// Emotion name.
    pub emotion: String,
    /// Components, frames x m, as projected.
    pub u: Vec<f32>,
}

/// The takes the timeline draws, as indices into `report.takes` (manifest order): up to five
/// sentences, each in the two emotions whose levels differ most, alternating. It needs only
/// the report, so a streamed analysis reads just these takes again for the chart.
pub fn timeline_takes(report: &Report) -> Vec<usize> {
    let takes = &report.takes;
    let mut names: Vec<(&String, &f64)> = report.levels.iter().collect();
    names.sort_by(|a, b| a.1.total_cmp(b.1));
    let pick: Vec<&str> = match (names.first(), names.last()) {
        (Some(lo), Some(hi)) if lo.0 != hi.0 => vec![lo.0.as_str(), hi.0.as_str()],
        _ => Vec::new(),
    };
    let mut out = Vec::new();
    let mut sentences: Vec<&str> = takes.iter().map(|t| t.sentence.as_str()).collect();
    sentences.dedup();
    for s in sentences {
        if out.len() >= 10 {
            break;
        }
        let of_sentence = || (0..takes.len()).filter(|&i| takes[i].sentence == s);
        if pick.is_empty() {
            out.extend(of_sentence().take(2));
            continue;
        }
        for e in &pick {
            out.extend(of_sentence().find(|&i| takes[i].emotion == *e));
        }
    }
    out
}

/// Figure 2: every component's series over alternating-emotion takes, one row per component,
/// with the takes shaded by emotion.
pub fn timeline_chart(report: &Report, shown: &[TimelineTake]) -> String {
    let m = report.components.len();
    let total: usize = shown.iter().map(|t| t.u.len() / m.max(1)).sum();
    let (w, row_h, left) = (1000.0, 70.0, 60.0);
    let h = row_h * m as f64 + 40.0;
    let mut svg = format!(
        r##"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="sans-serif"><rect width="100%" height="100%" fill="#fff"/>"##
    );
    let scale_x = (w - left - 10.0) / total.max(1) as f64;
    let mut x = left;
    let shades = ["#f0f0f0", "#c8c8c8"];
    let mut emotions: Vec<&str> = Vec::new();
    for t in shown {
        let frames = t.u.len() / m.max(1);
        if !emotions.contains(&t.emotion.as_str()) {
            emotions.push(&t.emotion);
        }
        let shade = shades[emotions.iter().position(|e| *e == t.emotion).unwrap_or(0) % 2];
        let _ = write!(
            svg,
            r##"<rect x="{x:.1}" y="20" width="{:.1}" height="{:.1}" fill="{shade}"><title>{} {}</title></rect><text x="{:.1}" y="14" font-size="9">{}</text>"##,
            frames as f64 * scale_x,
            row_h * m as f64,
            esc(&t.sentence),
            esc(&t.emotion),
            x + 2.0,
            esc(&t.emotion)
        );
        x += frames as f64 * scale_x;
    }
    for (k, comp) in report.components.iter().enumerate() {
        let y0 = 20.0 + row_h * k as f64;
        let values: Vec<f32> = shown
            .iter()
            .flat_map(|t| t.u.chunks_exact(m).map(move |row| row[k]))
            .collect();
        let max = values.iter().fold(1e-6f32, |a, v| a.max(v.abs()));
        let mut path = String::new();
        for (i, v) in values.iter().enumerate() {
            let px = left + i as f64 * scale_x;
            let py = y0 + row_h / 2.0 - f64::from(*v / max) * (row_h / 2.0 - 4.0);
            let _ = write!(path, "{}{px:.1},{py:.1}", if i == 0 { "M" } else { "L" });
        }
        let _ = write!(
            svg,
            r##"<text x="4" y="{:.1}" font-size="11">c{k}</text><text x="4" y="{:.1}" font-size="9" fill="{c}">{:?}</text><path d="{path}" fill="none" stroke="{c}" stroke-width="1"/>"##,
            y0 + row_h / 2.0,
            y0 + row_h / 2.0 + 12.0,
            comp.role,
            c = role_colour(comp.role)
        );
    }
    svg.push_str("</svg>");
    svg
}
