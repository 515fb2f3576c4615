//! `report.html`: both figures with short explanations and the metrics table.

use std::fmt::Write as _;

use super::svg::role_colour;
use super::Report;

/// The model's quality report: head decision, stability, residuals and warnings.
fn quality_section(q: &ica_core::quality::ModelQuality) -> String {
    if q.is_empty() {
        return "<h2>Model quality</h2><p>Not recorded: the model was trained before quality \
                reports existed.</p>"
            .into();
    }
    let mut out = String::from("<h2>Model quality</h2><ul>");
    if let Some(h) = &q.head {
        let _ = write!(
            out,
            "<li>Head ({}): {}</li>",
            esc(&h.source),
            esc(&h.verdict)
        );
    }
    if !q.stability.is_empty() {
        let s: Vec<String> = q
            .stability
            .iter()
            .enumerate()
            .map(|(i, v)| format!("c{i} {v:.2}"))
            .collect();
        let _ = write!(
            out,
            "<li>Stability across restarts (best-match |corr|): {}</li>",
            s.join(", ")
        );
    }
    let r: Vec<String> = q
        .residual_by_region_mm
        .iter()
        .map(|(n, v)| format!("{} {v:.2}", esc(n)))
        .collect();
    if !r.is_empty() {
        let _ = write!(
            out,
            "<li>Reconstruction residual (mm RMS per marker): {}</li>",
            r.join(", ")
        );
    }
    if let (Some(mm), Some(marker)) = (q.slow_residual_mm, &q.slow_residual_marker) {
        let _ = write!(
            out,
            "<li>Largest slow signal left out: {mm:.2} mm RMS at {}</li>",
            esc(marker)
        );
    }
    out.push_str("</ul>");
    if q.warnings.is_empty() {
        out.push_str("<p>No warnings.</p>");
    } else {
        out.push_str("<p><b>Warnings</b></p><ul>");
        for w in &q.warnings {
            let _ = write!(out, "<li>{}</li>", esc(&w.message));
        }
        out.push_str("</ul>");
    }
    out
}

/// The emotion space: the map (when there is one), the level table and the notes on emotions
/// that cannot be told apart; the main component's levels without a space.
fn space_section(report: &Report, levels: &str) -> String {
    let Some(space) = report.space.as_ref().filter(|s| !s.components.is_empty()) else {
        return format!("<ul>{levels}</ul>");
    };
    let comps: Vec<String> = space.components.iter().map(|k| format!("c{k}")).collect();
    let axes: Vec<String> = space.axes.iter().map(|k| format!("c{k}")).collect();
    format!(
        r#"<p>Components whose take levels differ between emotions (blocked F test over the
paired takes, p &lt; 0.001 over all components): {}; emotion axes (emotions explain at least
half of their levels): {}. Each emotion is a point in this space: the mean over its takes ± the
spread across them.</p>
<img src="emotion_map.svg" alt="emotion map: takes and emotion levels in the plane of the two strongest emotion directions">
{}
{}"#,
        comps.join(", "),
        axes.join(", "),
        super::map::level_table(report),
        fitted_section(space)
    )
}

/// The axes the edits use (fitted over every component) and whether the emotion components
/// alone would have been sound axes.
fn fitted_section(space: &super::space::EmotionSpace) -> String {
    let mut out = String::from("<h3>Axes of the edits</h3>");
    if let Some(c) = &space.conditioning {
        let verdict = if c.ill_conditioned {
            "<b>Ill-conditioned:</b> "
        } else {
            "Well-conditioned: "
        };
        let _ = write!(out, "<p>{verdict}{}.</p><ul>", esc(&c.note));
        let _ = write!(
            out,
            "<li>Condition number of the emotions' points on the emotion components: {:.1}              (above {} the components' levels move together)</li>",
            c.condition,
            super::space::CONDITION_LIMIT
        );
        for (a, b, r) in &c.collinear {
            let _ = write!(
                out,
                "<li>c{a} and c{b} move together over the takes: r = {r:.2}</li>"
            );
        }
        for (k, r) in &c.unstable {
            let _ = write!(
                out,
                "<li>c{k} is not found again by the other training restarts (best match {r:.2})</li>"
            );
        }
        out.push_str("</ul>");
    }
    let Some(b) = &space.basis else {
        out.push_str("<p>The session cannot tell the space's directions apart.</p>");
        return out;
    };
    let _ = write!(
        out,
        "<p>The edits use {} axes fitted over every component, so they do not depend on how ICA          split the emotion between components: the directions in which the takes' {} differ          between emotions, each kept while its F test passes ({}). A take's position is read          from its mean with the least noise the takes' means carry; each axis keeps the share of          a take's offset that persists into another emotion (persistence {}).</p>",
        b.axes.len(),
        if b.aligned {
            "levels, with each sentence's content matched frame by frame (DTW),"
        } else {
            "mean levels"
        },
        axis_tests(&b.tests),
        b.persistence
            .iter()
            .map(|p| format!("{p:.2}"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    out
}

/// Each fitted axis's F test, for the report.
fn axis_tests(tests: &[ica_core::interpret::AxisTest]) -> String {
    let text = tests.iter().enumerate().map(|(i, t)| {
        let kept = if t.kept { "kept" } else { "not kept" };
        let f = super::space::f_text(t.f);
        format!("e{}: F = {f}, p = {:.1e} ({kept})", i + 1, t.p)
    });
    text.collect::<Vec<_>>().join("; ")
}

/// Escapes text for HTML.
fn esc(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// One table row per component: its role, d_emotion, d_level, each region's metric, |M_k|.
fn metric_rows(report: &Report, regions: &[&String]) -> String {
    let mut rows = String::new();
    for c in &report.components {
        let _ = write!(
            rows,
            r#"<tr><td>c{}</td><td style="color:{}"><b>{:?}</b></td><td>{}</td>"#,
            c.index,
            role_colour(c.role),
            c.role,
            c.d_emotion.map_or("—".into(), |d| format!("{d:.4}"))
        );
        let _ = write!(
            rows,
            "<td>{}</td>",
            c.d_level.map_or("—".into(), |d| format!("{d:.4}"))
        );
        for r in regions {
            let _ = write!(rows, "<td>{:.4}</td>", c.d_region[*r]);
        }
        let _ = write!(rows, "<td>{:.2}</td></tr>", c.mixing_norm_mm);
    }
    rows
}

/// Each emotion's level as a list item.
fn level_items(report: &Report) -> String {
    report
        .levels
        .iter()
        .map(|(n, v)| format!("<li>{n}: {v:.4}</li>"))
        .collect()
}

/// What the session lacks (as `analyze` prints it), as a list; empty when nothing.
fn advice_section(report: &Report) -> String {
    if report.advice.is_empty() {
        return String::new();
    }
    let items: String = report
        .advice
        .iter()
        .map(|line| format!("<li>{}</li>", esc(line)))
        .collect();
    format!("<p><b>What the session lacks</b></p><ul class=\"advice\">{items}</ul>\n")
}

/// What the analysis says of the emotion component(s).
fn emotion_note(report: &Report) -> String {
    if report.emotion_note.is_empty() {
        format!("Emotion component(s): {:?}.", report.emotion_components)
    } else {
        report.emotion_note.clone()
    }
}

/// The report page; it references `components.svg` and `timeline.svg` beside it.
pub fn page(report: &Report) -> String {
    let regions: Vec<&String> = report
        .components
        .first()
        .map(|c| c.d_region.keys().collect())
        .unwrap_or_default();
    let rows = metric_rows(report, &regions);
    let header: String = regions.iter().map(|r| format!("<th>d_{r}</th>")).collect();
    let (levels, note) = (level_items(report), emotion_note(report));
    let t = &report.thresholds;
    format!(
        r#"<!doctype html>
<html><head><meta charset="utf-8"><title>emoshift analysis</title>
<style>body{{font-family:sans-serif;max-width:1050px;margin:2em auto}}table{{border-collapse:collapse}}td,th{{border:1px solid #ccc;padding:2px 6px;text-align:right}}</style>
</head><body>
<h1>emoshift analysis</h1>
<p>Model <code>{model}</code>, session <code>{manifest}</code>: {m} components, {pairs} emotion pairs.</p>
<h2>Which component does what</h2>
<p>(a) <b>d_emotion</b>: for takes of the same sentence in two emotions, aligned by dynamic time
warping, the RMS difference of each component. A clear peak marks the emotion component.
(b–d) <b>region metrics</b>: how much adding one component moves the mouth, eyebrow and eyelid
markers towards the full reconstruction (|d_region,i|, Eq. 4 of the method).
Bars are coloured by the role given.</p>
<img src="components.svg" alt="bar charts of d_emotion, d_mouth, d_eyebrows and d_eyelids per component">
<p>{note}</p>
{advice}<h2>Components over time</h2>
<p>Each row is one component over takes that alternate between the two most different emotions
(shaded backgrounds). The emotion component jumps between levels when the emotion changes; speech
components follow the words.</p>
<img src="timeline.svg" alt="component series over alternating-emotion takes">
<h2>Emotion space</h2>
{space}
<h2>Metrics</h2>
<table><tr><th>component</th><th>role</th><th>d_emotion</th><th>d_level</th>{header}<th>|M_k| mm</th></tr>{rows}</table>
{quality}
<p>Thresholds: emotion when d_level (RMS difference of paired take means) ≥ {r1} × its median
and ≥ {r2} × its max; otherwise a component takes the role of the region holding ≥ {r3} of its
summed |d_region| over mouth, eyebrows and eyelids, if that |d_region| is ≥ {r4} × the region's
largest; else other.</p>
</body></html>
"#,
        model = report.model,
        manifest = report.manifest,
        quality = quality_section(&report.quality),
        space = space_section(report, &levels),
        advice = advice_section(report),
        m = report.components.len(),
        pairs = report.pairs.len(),
        r1 = t.emotion_peak_ratio,
        r2 = t.emotion_share_of_max,
        r3 = t.region_share_of_component,
        r4 = t.region_floor_of_max,
    )
}
