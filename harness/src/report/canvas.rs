//! What both timing diagrams draw on (a device's cycles in `diagram`, a
//! client's tasks in `task_diagram`): the SVG canvas with its labelled rows,
//! a column's head, the bus's frames inside a column, and SVG escaping.

use std::fmt::Write as _;

use crate::outcome::BusFrame;

pub(super) const LABEL_WIDTH: f64 = 300.0;
pub(super) const CELL: f64 = 150.0;
pub(super) const ROW: f64 = 26.0;
pub(super) fn esc(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// The frames that ended from `previous` to `now`, placed inside their
/// column (at `x`, row top `y`) by when they ended.
pub(super) fn bus_frames(
    svg: &mut String,
    x: f64,
    (previous, now): (canif_model::Nanos, canif_model::Nanos),
    frames: &[BusFrame],
    y: f64,
) {
    let span = now.saturating_sub(previous).max(1) as f64;
    for frame in frames {
        let at = (frame.end.saturating_sub(previous) as f64 / span).clamp(0.0, 1.0);
        let fx = x + 2.0 + (CELL - 40.0) * at;
        let colour = if frame.from_iut { "#36c" } else { "#999" };
        let id = frame.text.split('#').next().unwrap_or("");
        let _ = writeln!(
            svg,
            "<rect class=\"bus-frame\" x=\"{fx:.1}\" y=\"{}\" width=\"3\" height=\"14\" fill=\"{colour}\"><title>{}</title></rect>",
            y + 4.0,
            esc(&frame.text)
        );
        let _ = writeln!(
            svg,
            "<text x=\"{:.1}\" y=\"{}\" font-size=\"8\" fill=\"{colour}\">{}</text>",
            fx + 4.0,
            y + 14.0,
            esc(id)
        );
    }
}

/// An SVG of `width` × `height`, scaled to the page and never wider (the
/// failing column, last, stays in view), with a labelled line per row.
pub(super) fn canvas(class: &str, (width, height): (f64, f64), rows: &[&str]) -> String {
    let mut svg = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" class=\"{class}\" width=\"{width}\" height=\"{height}\" viewBox=\"0 0 {width} {height}\" style=\"max-width:100%;height:auto\" font-family=\"monospace\" font-size=\"11\">\n"
    );
    for (i, name) in rows.iter().enumerate() {
        let y = ROW * (i as f64 + 1.5);
        let _ = writeln!(svg, "<text x=\"4\" y=\"{}\">{}</text>", y + 16.0, esc(name));
        let _ = writeln!(
            svg,
            "<line x1=\"0\" y1=\"{y}\" x2=\"{width}\" y2=\"{y}\" stroke=\"#ddd\"/>"
        );
    }
    svg
}

/// A column's head: what it is and when, bold for the failing one.
pub(super) fn column_head(
    svg: &mut String,
    x: f64,
    failing: bool,
    what: &str,
    time: canif_model::Nanos,
) {
    let _ = writeln!(
        svg,
        "<text x=\"{}\" y=\"18\" font-weight=\"{}\">{what} · {:.3} ms</text>",
        x + 4.0,
        if failing { "bold" } else { "normal" },
        time as f64 / 1e6
    );
}
