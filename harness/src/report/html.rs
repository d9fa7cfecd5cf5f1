//! The report for people: `report.html` with a timing diagram of each
//! failure, and the one-line and detailed texts of a failure.

use canif_spec::Catalogue;

use super::RunReport;
use crate::outcome::Failure;
use crate::suite::Verdict;

/// One line: where and what.
pub fn headline(failure: &Failure) -> String {
    format!(
        "{} at cycle {}: {} differs ({})",
        failure.scenario,
        failure.cycle,
        failure.what,
        canif_spec::ReqId::join(&failure.requirements, ", ")
    )
}

/// Expected and actual, and the cycles before.
pub fn details(failure: &Failure) -> String {
    format!(
        "{}\n  expected: {}\n  actual:   {}\n  at t = {:.6} ms\ncycles before:\n  {}",
        headline(failure),
        failure.expected,
        failure.actual,
        failure.time as f64 / 1e6,
        failure.context.join("\n  ")
    )
}

fn esc(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// A timing diagram of a failure's last cycles: the PLC's outputs, then the
/// input header as the model expected it and as the IUT gave it (a red cell
/// where they differ), then the frames on the bus against time.
pub fn timing_diagram(failure: &Failure) -> String {
    let cycles = &failure.timeline;
    if cycles.is_empty() {
        return String::new();
    }
    let (label_width, cell, row) = (285.0, 150.0, 26.0);
    let rows = [
        "Outputs.TxCounter / RxCounter / NoOfTx",
        "Inputs.TxCounter (expected | actual)",
        "Inputs.RxCounter (expected | actual)",
        "NoOfRxMessages (expected | actual)",
        "TransactionNumber (expected | actual)",
        "bus (blue: IUT, grey: other nodes)",
    ];
    let width = label_width + cell * cycles.len() as f64 + 10.0;
    let height = row * (rows.len() as f64 + 1.5) + 20.0;
    let mut svg = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" class=\"timing\" width=\"{width}\" height=\"{height}\" font-family=\"monospace\" font-size=\"11\">\n"
    );
    for (i, name) in rows.iter().enumerate() {
        let y = row * (i as f64 + 1.5);
        svg.push_str(&format!(
            "<text x=\"4\" y=\"{}\">{}</text>\n",
            y + 16.0,
            esc(name)
        ));
        svg.push_str(&format!(
            "<line x1=\"0\" y1=\"{y}\" x2=\"{width}\" y2=\"{y}\" stroke=\"#ddd\"/>\n"
        ));
    }
    for (c, view) in cycles.iter().enumerate() {
        let x = label_width + cell * c as f64;
        let failing = c + 1 == cycles.len();
        svg.push_str(&format!(
            "<text x=\"{}\" y=\"18\" font-weight=\"{}\">cycle {} · {:.3} ms</text>\n",
            x + 4.0,
            if failing { "bold" } else { "normal" },
            view.cycle,
            view.time as f64 / 1e6
        ));
        if failing {
            svg.push_str(&format!(
                "<rect class=\"failing-cycle\" x=\"{x}\" y=\"2\" width=\"{cell}\" height=\"{}\" fill=\"none\" stroke=\"#c00\" stroke-width=\"2\"/>\n",
                height - 4.0
            ));
        }
        let o = view.outputs;
        svg.push_str(&format!(
            "<text x=\"{}\" y=\"{}\">{} / {} / {}</text>\n",
            x + 4.0,
            row * 1.5 + 16.0,
            o.tx_counter,
            o.rx_counter,
            o.no_of_tx_messages
        ));
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
            let y = row * (field as f64 + 2.5);
            let (e, a) = (expected[field], actual[field]);
            if e != a {
                svg.push_str(&format!("<rect class=\"mismatch\" x=\"{x}\" y=\"{y}\" width=\"{cell}\" height=\"{row}\" fill=\"#fcc\"/>\n"));
            }
            svg.push_str(&format!(
                "<text x=\"{}\" y=\"{}\">{e} | {a}</text>\n",
                x + 4.0,
                y + 16.0
            ));
        }
        let previous = if c == 0 {
            view.time.saturating_sub(1_000_000)
        } else {
            cycles[c - 1].time
        };
        let span = view.time.saturating_sub(previous).max(1) as f64;
        let y = row * 6.5;
        for frame in &view.frames {
            let (end, from_iut, text) = (&frame.end, &frame.from_iut, &frame.text);
            let fx = x + cell * (end.saturating_sub(previous) as f64 / span).min(1.0) - cell + 2.0;
            let fx = fx.max(x - cell + 2.0);
            let colour = if *from_iut { "#36c" } else { "#999" };
            let id = text.split('#').next().unwrap_or("");
            svg.push_str(&format!(
                "<rect x=\"{fx:.1}\" y=\"{}\" width=\"3\" height=\"14\" fill=\"{colour}\"><title>{}</title></rect>\n",
                y + 4.0,
                esc(text)
            ));
            svg.push_str(&format!(
                "<text x=\"{:.1}\" y=\"{}\" font-size=\"8\" fill=\"{colour}\">{}</text>\n",
                fx + 4.0,
                y + 14.0,
                esc(id)
            ));
        }
    }
    svg.push_str("</svg>\n");
    svg
}

impl RunReport {
    /// `report.html`: one self-contained page (no network): verdicts per
    /// requirement and per scenario, filterable, and each failure with its
    /// timing diagram.
    pub fn html(&self, catalogue: &Catalogue) -> String {
        let totals = self.totals();
        let mut rows = String::new();
        for profile in &self.profiles {
            for requirement in catalogue.requirements() {
                let Some(verdict) = profile.verdicts.get(&requirement.id) else {
                    continue;
                };
                let reason = match verdict {
                    Verdict::NotApplicable(r) | Verdict::NotTestable(r) | Verdict::Error(r) => {
                        r.clone()
                    }
                    Verdict::Fail(indexes) => headline(&profile.failures[indexes[0]]),
                    Verdict::Pass => String::new(),
                };
                rows.push_str(&format!(
                    "<tr class=\"{}\"><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>\n",
                    verdict.label().replace(' ', "-"),
                    esc(&profile.profile),
                    requirement.id,
                    verdict.label(),
                    esc(&requirement.statement),
                    esc(&reason)
                ));
            }
        }
        for scenario in &self.scenarios {
            let (label, reason) = match &scenario.outcome {
                Ok(()) => ("pass", String::new()),
                Err(report) => (
                    "fail",
                    report
                        .lines()
                        .find(|l| l.contains("Step panicked") || l.contains('✘'))
                        .unwrap_or("")
                        .trim()
                        .to_string(),
                ),
            };
            rows.push_str(&format!(
                "<tr class=\"{label} scenario\"><td>{}</td><td>{}:{}</td><td>{label}</td><td>{}</td><td>{}</td></tr>\n",
                esc(&scenario.suite),
                esc(&scenario.file),
                scenario.line,
                esc(&format!("{} ({})", scenario.name, scenario.requirements.join(", "))),
                esc(&reason)
            ));
        }
        let mut failures = String::new();
        for profile in &self.profiles {
            for failure in &profile.failures {
                failures.push_str(&format!(
                    "<section class=\"failure\"><h3>{} — {}</h3>\n<p>expected <code>{}</code><br>actual <code>{}</code></p>\n{}<pre>{}</pre></section>\n",
                    esc(&profile.profile),
                    esc(&headline(failure)),
                    esc(&failure.expected),
                    esc(&failure.actual),
                    timing_diagram(failure),
                    esc(&details(failure))
                ));
            }
        }
        for scenario in self.scenarios.iter().filter(|s| s.outcome.is_err()) {
            failures.push_str(&format!(
                "<section class=\"failure\"><h3>{} — scenario {}:{} {}</h3><pre>{}</pre></section>\n",
                esc(&scenario.suite),
                esc(&scenario.file),
                scenario.line,
                esc(&scenario.name),
                esc(scenario.outcome.as_ref().err().map_or("", String::as_str))
            ));
        }
        format!(
            r#"<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>canif report — {iut}</title>
<style>
body{{font-family:sans-serif;margin:1.5em}} table{{border-collapse:collapse;font-size:13px}} td,th{{border:1px solid #ddd;padding:2px 6px;vertical-align:top}}
tr.fail td:nth-child(3),tr.error td:nth-child(3){{color:#b00;font-weight:bold}} tr.pass td:nth-child(3){{color:#070}} tr.not-applicable,tr.not-testable{{color:#888}}
pre{{background:#f6f6f6;padding:6px;overflow-x:auto;font-size:12px}} svg.timing{{border:1px solid #ccc;background:#fff;margin:6px 0}}
</style></head>
<body>
<h1>canif conformance run</h1>
<p><b>{verdict}</b> — IUT <code>{iut}</code> on {bus}, seed {seed}: {pass} pass, {fail} fail, {error} error, {na} not applicable, {nt} not testable; Gherkin scenarios: {scenarios} run, {failed} failed.</p>
<h2>Failures</h2>
{failures_or_none}
<h2>Verdicts</h2>
<p><label>Filter: <input id="filter" type="search" placeholder="profile, id, verdict, words"></label>
<label><input id="only-problems" type="checkbox"> only fail and error</label> <span id="shown"></span></p>
<table id="verdicts"><thead><tr><th>profile / suite</th><th>requirement / scenario</th><th>verdict</th><th>statement</th><th>why</th></tr></thead>
<tbody>
{rows}</tbody></table>
<script>
window.addEventListener('error', function (e) {{ document.body.dataset.errors = (document.body.dataset.errors || '') + e.message + ';'; }});
(function () {{
  var input = document.getElementById('filter'), problems = document.getElementById('only-problems');
  var rows = Array.prototype.slice.call(document.querySelectorAll('#verdicts tbody tr'));
  function apply() {{
    var words = input.value.toLowerCase().split(/\s+/).filter(Boolean), shown = 0;
    rows.forEach(function (row) {{
      var text = row.textContent.toLowerCase();
      var ok = words.every(function (w) {{ return text.indexOf(w) >= 0; }});
      if (problems.checked) ok = ok && (row.classList.contains('fail') || row.classList.contains('error'));
      row.style.display = ok ? '' : 'none';
      if (ok) shown++;
    }});
    document.getElementById('shown').textContent = shown + ' of ' + rows.length + ' shown';
  }}
  input.addEventListener('input', apply);
  problems.addEventListener('change', apply);
  apply();
  document.body.dataset.ready = 'yes';
}})();
</script>
</body></html>
"#,
            iut = esc(&self.iut),
            bus = esc(&self.bus),
            seed = self.seed,
            verdict = match self.exit_code() {
                0 => "CONFORMS",
                1 => "DOES NOT CONFORM",
                _ => "ERROR",
            },
            pass = totals.pass,
            fail = totals.fail,
            error = totals.error,
            na = totals.not_applicable,
            nt = totals.not_testable,
            scenarios = self.scenarios.len(),
            failed = self.failed_scenarios(),
            failures_or_none = if failures.is_empty() {
                "<p>None.</p>".to_string()
            } else {
                failures
            },
            rows = rows,
        )
    }
}
