//! The timing diagram of a failure's last cycles, as SVG: the PLC's outputs,
//! the input header as the model expected it and as the IUT gave it (a red
//! cell where they differ), the frames that ended on the bus in each cycle,
//! and, in the failing cycle, the failing frame byte by byte with the bytes
//! that differ highlighted.

use std::fmt::Write as _;

use canif_model::frame::Frame;

use crate::outcome::{BusFrame, CycleView, Failure, Timeline};

pub(super) const LABEL_WIDTH: f64 = 300.0;
pub(super) const CELL: f64 = 150.0;
pub(super) const ROW: f64 = 26.0;
/// Width of one byte as `AB ` in the 11-pixel monospace font.
const BYTE_WIDTH: f64 = 20.0;

pub(super) fn esc(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// A frame's identifier and bytes as SVG text, the bytes that differ from
/// `other` (or that `other` lacks) marked `differs`.
fn frame_text(frame: Option<&Frame>, other: Option<&Frame>) -> String {
    let Some(frame) = frame else {
        return "<tspan class=\"differs\" fill=\"#c00\" font-weight=\"bold\">no frame</tspan>"
            .into();
    };
    let id_differs = other.is_none_or(|o| o.id != frame.id || o.kind != frame.kind);
    let mut text = format!(
        "<tspan{}>{:0width$X}{}</tspan> [{}] ",
        if id_differs {
            " class=\"differs\" fill=\"#c00\" font-weight=\"bold\""
        } else {
            ""
        },
        frame.id.raw(),
        if frame.is_remote() { " R" } else { "" },
        frame.len(),
        width = if frame.id.is_extended() { 8 } else { 3 }
    );
    for (i, byte) in frame.data().iter().enumerate() {
        let differs = other.is_none_or(|o| o.data().get(i) != Some(byte));
        let _ = write!(
            text,
            "<tspan{}>{byte:02X}</tspan> ",
            if differs {
                " class=\"differs\" fill=\"#c00\" font-weight=\"bold\""
            } else {
                ""
            }
        );
    }
    text
}

/// The failure's diagram, drawn for the side under test.
pub fn timing_diagram(failure: &Failure) -> String {
    match &failure.timeline {
        Timeline::Cycles(cycles) if !cycles.is_empty() => cycle_diagram(failure, cycles),
        Timeline::Tasks { tasks, row } if !tasks.is_empty() => {
            super::task_diagram::task_diagram(failure, tasks, *row)
        }
        _ => String::new(),
    }
}

/// A device's failure: the model's input header against the IUT's.
fn cycle_diagram(failure: &Failure, cycles: &[CycleView]) -> String {
    let mut rows = vec![
        "Outputs.TxCounter / RxCounter / NoOfTx",
        "Inputs.TxCounter (expected | actual)",
        "Inputs.RxCounter (expected | actual)",
        "NoOfRxMessages (expected | actual)",
        "TransactionNumber (expected | actual)",
        "bus (blue: IUT, grey: other nodes)",
    ];
    if failure.frames.is_some() {
        rows.extend(["failing frame, expected", "failing frame, actual"]);
    }
    let longest = failure.frames.as_ref().map_or(0, |f| {
        [f.expected, f.actual]
            .iter()
            .flatten()
            .map(|frame| frame.len() + 6)
            .max()
            .unwrap_or(2)
    });
    let last_x = LABEL_WIDTH + CELL * (cycles.len() - 1) as f64;
    let width =
        (LABEL_WIDTH + CELL * cycles.len() as f64).max(last_x + BYTE_WIDTH * longest as f64) + 10.0;
    let height = ROW * (rows.len() as f64 + 1.5) + 20.0;
    let mut svg = canvas("timing", (width, height), &rows);
    for (c, view) in cycles.iter().enumerate() {
        let x = LABEL_WIDTH + CELL * c as f64;
        let failing = c + 1 == cycles.len();
        column_head(
            &mut svg,
            x,
            failing,
            &format!("cycle {}", view.cycle),
            view.time,
        );
        if failing {
            let _ = writeln!(
                svg,
                "<rect class=\"failing-cycle\" x=\"{x}\" y=\"2\" width=\"{CELL}\" height=\"{}\" fill=\"none\" stroke=\"#c00\" stroke-width=\"2\"/>",
                ROW * 7.5 - 4.0
            );
        }
        let o = view.outputs;
        let _ = writeln!(
            svg,
            "<text x=\"{}\" y=\"{}\">{} / {} / {}</text>",
            x + 4.0,
            ROW * 1.5 + 16.0,
            o.tx_counter,
            o.rx_counter,
            o.no_of_tx_messages
        );
        let fields = |h: &canif_model::image::InputHeader| {
            [
                h.tx_counter,
                h.rx_counter,
                h.no_of_rx_messages,
                h.transaction_number.unwrap_or(0),
            ]
        };
        let (expected, actual) = (fields(&view.expected), fields(&view.actual));
        for field in 0..4 {
            let y = ROW * (field as f64 + 2.5);
            let (e, a) = (expected[field], actual[field]);
            if e != a {
                let _ = writeln!(svg, "<rect class=\"mismatch\" x=\"{x}\" y=\"{y}\" width=\"{CELL}\" height=\"{ROW}\" fill=\"#fcc\"/>");
            }
            let _ = writeln!(
                svg,
                "<text x=\"{}\" y=\"{}\">{e} | {a}</text>",
                x + 4.0,
                y + 16.0
            );
        }
        // The frames the text lists under this cycle.
        let previous = match c {
            0 => view.time.saturating_sub(1_000_000),
            _ => cycles[c - 1].time,
        };
        bus_frames(&mut svg, x, (previous, view.time), &view.frames, ROW * 6.5);
        let y = ROW * 6.5;
        if let (true, Some(frames)) = (failing, &failure.frames) {
            let _ = writeln!(
                svg,
                "<rect class=\"failing-frame\" x=\"{}\" y=\"{}\" width=\"6\" height=\"14\" fill=\"#c00\"><title>the failing frame</title></rect>",
                x + CELL - 10.0,
                y + 4.0
            );
            for (row, (frame, other)) in [
                (frames.expected.as_ref(), frames.actual.as_ref()),
                (frames.actual.as_ref(), frames.expected.as_ref()),
            ]
            .into_iter()
            .enumerate()
            {
                let _ = writeln!(
                    svg,
                    "<text class=\"failing-frame-bytes\" x=\"{}\" y=\"{}\">{}</text>",
                    x + 4.0,
                    ROW * (7.5 + row as f64) + 16.0,
                    frame_text(frame, other)
                );
            }
        }
    }
    svg.push_str("</svg>\n");
    svg
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
