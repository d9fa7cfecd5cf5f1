//! The timing diagram of a client's failure, as SVG: per task, the input
//! header the master handed it, the output header it left, what its
//! application asked and got, and the frames the device sent; in the failing
//! task, the row the breach is about as expected | actual. The failing task
//! is the last column and its text runs leftwards, so it stays in view.

use std::fmt::Write as _;

use super::canvas::{bus_frames, canvas, column_head, esc, CELL, LABEL_WIDTH, ROW};
use crate::outcome::{Failure, TaskRow, TaskView};

const ROWS: [(&str, Option<TaskRow>); 6] = [
    ("Inputs as handed: Tx / Rx / NoOfRx", None),
    ("Outputs.TxCounter", Some(TaskRow::TxCounter)),
    ("Outputs.RxCounter", Some(TaskRow::RxCounter)),
    ("NoOfTxMessages", Some(TaskRow::NoOfTxMessages)),
    ("application: asked | delivered", Some(TaskRow::Application)),
    ("bus (blue: device, grey: other nodes)", Some(TaskRow::Bus)),
];

pub(super) fn task_diagram(failure: &Failure, tasks: &[TaskView], row: TaskRow) -> String {
    let width = LABEL_WIDTH + CELL * tasks.len() as f64 + 10.0;
    // The rows, then the breach: expected and actual, under the failing task.
    let height = ROW * (ROWS.len() as f64 + 3.5) + 20.0;
    let labels: Vec<&str> = ROWS.iter().map(|(label, _)| *label).collect();
    let mut svg = canvas("timing tasks", (width, height), &labels);
    for (t, view) in tasks.iter().enumerate() {
        let x = LABEL_WIDTH + CELL * t as f64;
        let failing = t + 1 == tasks.len();
        column_head(
            &mut svg,
            x,
            failing,
            &format!("task {}", view.task),
            view.time,
        );
        let (i, o) = (view.inputs, view.outputs);
        let cells = [
            format!(
                "{} / {} / {}",
                i.tx_counter, i.rx_counter, i.no_of_rx_messages
            ),
            o.tx_counter.to_string(),
            o.rx_counter.to_string(),
            o.no_of_tx_messages.to_string(),
            format!("+{} | {}", view.requests, view.delivered),
        ];
        for (r, text) in cells.iter().enumerate() {
            let y = ROW * (r as f64 + 1.5);
            if failing && ROWS[r].1 == Some(row) {
                let _ = writeln!(
                    svg,
                    "<rect class=\"breach-row\" x=\"{x}\" y=\"{y}\" width=\"{CELL}\" height=\"{ROW}\" fill=\"#fcc\"/>"
                );
            }
            let _ = writeln!(
                svg,
                "<text x=\"{}\" y=\"{}\">{}</text>",
                x + 4.0,
                y + 16.0,
                esc(text)
            );
        }
        let previous = match t {
            0 => view.time.saturating_sub(1_000_000),
            _ => tasks[t - 1].time,
        };
        bus_frames(&mut svg, x, (previous, view.time), &view.frames, ROW * 6.5);
        if failing {
            let _ = writeln!(
                svg,
                "<rect class=\"failing-task\" x=\"{x}\" y=\"2\" width=\"{CELL}\" height=\"{}\" fill=\"none\" stroke=\"#c00\" stroke-width=\"2\"/>",
                ROW * 7.5 - 4.0
            );
            // Anchored at the failing task's right edge: long text runs
            // back over the earlier tasks, never off the picture.
            let right = x + CELL - 4.0;
            for (n, (label, text)) in [
                ("", failure.what.as_str()),
                ("expected: ", failure.expected.as_str()),
                ("actual: ", failure.actual.as_str()),
            ]
            .into_iter()
            .enumerate()
            {
                let _ = writeln!(
                    svg,
                    "<text class=\"breach\" x=\"{right}\" y=\"{}\" text-anchor=\"end\"{}>{}{}</text>",
                    ROW * (7.5 + n as f64) + 16.0,
                    if n == 2 { " fill=\"#c00\" font-weight=\"bold\"" } else { "" },
                    label,
                    esc(text)
                );
            }
        }
    }
    svg.push_str("</svg>\n");
    svg
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::outcome::{BusFrame, Timeline};
    use canif_model::image::{InputHeader, OutputHeader};

    fn task(n: u64) -> TaskView {
        TaskView {
            task: n,
            time: n * 1_000_000,
            inputs: InputHeader {
                tx_counter: n as u16,
                ..InputHeader::default()
            },
            outputs: OutputHeader {
                tx_counter: n as u16 + 1,
                rx_counter: 7,
                no_of_tx_messages: 2,
            },
            requests: 3,
            delivered: 1,
            frames: vec![BusFrame {
                end: n * 1_000_000 - 10,
                from_iut: true,
                text: "123#AB".into(),
            }],
        }
    }

    #[test]
    fn a_client_failure_is_drawn_with_its_rows_and_the_breach_in_the_failing_task() {
        let failure = Failure {
            requirements: vec![canif_spec::ReqId::new("CL-RX-001")],
            scenario: "s".into(),
            cycle: 3,
            time: 3_000_000,
            what: "Outputs.RxCounter".into(),
            expected: "Inputs.RxCounter 8".into(),
            actual: "7".into(),
            context: Vec::new(),
            timeline: Timeline::Tasks {
                tasks: (1..=3).map(task).collect(),
                row: TaskRow::RxCounter,
            },
            frames: None,
            images: None,
            rest: crate::verdict::Rest::Stopped,
            further: Vec::new(),
        };
        let svg = super::super::timing_diagram(&failure);
        assert!(svg.contains("Inputs as handed"), "{svg}");
        assert!(!svg.contains("(expected | actual)"), "device rows: {svg}");
        assert!(svg.contains("task 3 · 3.000 ms"));
        assert!(svg.contains("+3 | 1"));
        // The breach row of the failing task only, and the breach itself.
        assert_eq!(svg.matches("class=\"breach-row\"").count(), 1);
        let highlighted = svg.find("class=\"breach-row\" x=\"600\" y=\"91\"");
        assert!(highlighted.is_some(), "{svg}");
        assert!(svg.contains("expected: Inputs.RxCounter 8"));
        assert!(svg.contains("text-anchor=\"end\""));
        assert_eq!(svg.matches("class=\"bus-frame\"").count(), 3);
    }
}
