//! The timing diagram of a failure's last cycles, as SVG: the PLC's outputs,
//! the input header as the model expected it and as the IUT gave it (a red
//! cell where they differ), the frames that ended on the bus in each cycle,
//! and, in the failing cycle, the failing frame byte by byte with the bytes
//! that differ highlighted.

use std::fmt::Write as _;

use canif_model::frame::Frame;

use super::canvas::{bus_frames, canvas, column_head, CELL, LABEL_WIDTH, ROW};
use crate::outcome::{CycleView, Failure, Timeline};

/// Width of one byte as `AB ` in the 11-pixel monospace font.
const BYTE_WIDTH: f64 = 20.0;

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
