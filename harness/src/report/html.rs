//! `report.html`: one self-contained page (no network) with the run's
//! metadata, a summary per profile, every failing requirement and its cause,
//! each failure with its timing diagram, errors grouped by cause, and every
//! verdict linked to the checks it rests on.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use canif_spec::Catalogue;

use super::canvas::esc;
pub(super) use super::diagram::timing_diagram;
use super::summary::utc;
use super::RunReport;
use crate::verdict::{CheckResult, Evidence, Verdict, VerdictKind};

/// The anchor of a check on a profile.
fn anchor(profile: &str, index: usize) -> String {
    format!(
        "check-{}-{index}",
        profile.replace(|c: char| !c.is_ascii_alphanumeric(), "-")
    )
}

impl RunReport {
    pub fn html(&self, catalogue: &Catalogue) -> String {
        let m = &self.meta;
        let meta = self.meta_rows();
        let profiles = self.profile_rows();
        let (problems, not_served, advisories) = self.listed(catalogue);
        let (checks, failures) = self.checks_and_failures();
        let errors = self.error_items();
        let verdicts = self.verdicts_by_area(catalogue);
        let none = |html: String| {
            if html.is_empty() {
                "<p>None.</p>".to_string()
            } else {
                html
            }
        };
        format!(
            r#"<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>canif report — {iut}</title>
<style>
body{{font-family:sans-serif;margin:1.5em}} table{{border-collapse:collapse;font-size:13px}} td,th{{border:1px solid #ddd;padding:2px 6px;vertical-align:top;text-align:left}}
tr.fail td:nth-child(3),tr.error td:nth-child(3),td.fail,td.error,span.fail,span.error{{color:#b00;font-weight:bold}} tr.pass td:nth-child(3),td.pass,span.pass{{color:#070}} td.not-run,span.not-run{{color:#a60}} tr.not-applicable,tr.not-testable,tr.not-run{{color:#888}}
details.area{{margin:4px 0;border:1px solid #ddd;padding:2px 6px}} details.area>summary{{font-weight:bold;cursor:pointer}} details.others>summary{{cursor:pointer;color:#555}}
pre{{background:#f6f6f6;padding:6px;overflow-x:auto;font-size:12px}} svg.timing{{border:1px solid #ccc;background:#fff;margin:6px 0}} td.evidence{{font-size:11px}}
</style></head>
<body>
<h1>canif conformance run</h1>
<p id="headline"><b>{headline}</b>: {totals}.</p>
<table id="meta">{meta}</table>
<h2>Profiles</h2>
<table id="profiles"><tr><th>profile</th><th>pass</th><th>fail</th><th>error</th><th>not applicable</th><th>not run</th><th>not testable</th><th>scenarios</th><th>Gherkin scenarios</th><th>checks</th><th>cycles</th><th>frames checked</th></tr>
{profiles}</table>
{not_served}{advisories}<h2>Failing and erring requirements</h2>
{problems}
<h2>Failures</h2>
{failures}
<h2>Errors</h2>
{errors}
<h2>Verdicts by area</h2>
<p><label>Filter: <input id="filter" type="search" placeholder="profile, id, verdict, words"></label>
<label><input id="only-problems" type="checkbox"> only fail and error</label> <span id="shown"></span></p>
<p class="legend">Areas with a failure or an error come first and open; in each, fail and error first, the other verdicts folded below.</p>
<div id="verdicts">
{verdicts}</div>
<h2>Checks</h2>
<table id="checks"><thead><tr><th>profile</th><th>check</th><th>outcome</th><th>exercises</th><th>cause</th></tr></thead>
<tbody>
{checks}</tbody></table>
<h2>Sources</h2>
<table id="sources"><tr><th>document</th><th>kept as</th></tr>
{sources}</table>
<script>
window.addEventListener('error', function (e) {{ document.body.dataset.errors = (document.body.dataset.errors || '') + e.message + ';'; }});
(function () {{
  var input = document.getElementById('filter'), problems = document.getElementById('only-problems');
  var rows = Array.prototype.slice.call(document.querySelectorAll('#verdicts tbody tr'));
  var folds = Array.prototype.slice.call(document.querySelectorAll('#verdicts details'));
  function apply() {{
    var words = input.value.toLowerCase().split(/\s+/).filter(Boolean), shown = 0;
    // A search opens every fold, so that what it finds is seen.
    if (words.length) folds.forEach(function (d) {{ d.open = true; }});
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
            iut = esc(&m.iut),
            sources = catalogue
                .sources
                .iter()
                .map(|s| format!(
                    "<tr><td>{}</td><td>{}</td></tr>",
                    esc(&s.title),
                    esc(&s.file)
                ))
                .collect::<String>(),
            headline = esc(&self.headline()),
            totals = esc(&self.totals_line()),
            problems = if problems.is_empty() {
                "<p>None.</p>".to_string()
            } else {
                format!("<ul id=\"problems\">{problems}</ul>")
            },
            failures = none(failures),
            errors = if errors.is_empty() {
                "<p>None.</p>".to_string()
            } else {
                format!("<ul>{errors}</ul>")
            },
        )
    }
}

impl RunReport {
    /// The run's metadata, one table row each.
    fn meta_rows(&self) -> String {
        let m = &self.meta;
        let mut meta = String::new();
        for (name, value) in [
            ("implementation", m.iut.clone()),
            (
                "product",
                m.product.as_ref().map_or("not declared".into(), |p| {
                    format!("{} {}", p.name, p.version)
                }),
            ),
            ("side / suite", format!("{} / {:?}", m.side, m.suite)),
            (
                "master models",
                if m.masters.is_empty() {
                    "not applicable (device side)".into()
                } else {
                    m.masters.join(", ")
                },
            ),
            ("bus", m.bus.clone()),
            ("seed", m.seed.to_string()),
            ("started", utc(m.started_unix)),
            ("canif", format!("{} ({})", m.canif_version, m.canif_commit)),
            ("catalogue SHA-256", m.catalogue_sha256.clone()),
            (
                "left out",
                m.left_out.clone().unwrap_or_else(|| "nothing".into()),
            ),
            ("wall time", format!("{} ms", self.wall_time_ms)),
        ] {
            let _ = writeln!(meta, "<tr><th>{name}</th><td>{}</td></tr>", esc(&value));
        }
        meta
    }

    /// One row per profile: its verdicts counted, what it ran.
    fn profile_rows(&self) -> String {
        let mut profiles = String::new();
        for p in &self.profiles {
            let _ = write!(profiles, "<tr><td>{}</td>", esc(&p.profile));
            for kind in VerdictKind::ALL {
                // A count is coloured by its verdict only when there is one:
                // a zero fail is not alarming.
                let count = p.count(kind);
                match count {
                    0 => profiles.push_str("<td>0</td>"),
                    _ => {
                        let class = kind.label().replace(' ', "-");
                        let _ = write!(profiles, "<td class=\"{class}\">{count}</td>");
                    }
                }
            }
            let _ = writeln!(
                profiles,
                "<td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
                p.ran.tally.scenarios,
                p.ran.tally.gherkin_scenarios,
                p.ran.checks.len(),
                p.ran.tally.cycles,
                p.ran.tally.frames_checked
            );
        }
        profiles
    }

    /// The failing and erring requirements, what is not served, the
    /// advisories: each a list, or nothing.
    fn listed(&self, catalogue: &Catalogue) -> (String, String, String) {
        let problems: String = self
            .problems(catalogue)
            .iter()
            .map(|problem| format!("<li>{}</li>\n", esc(&problem.to_string())))
            .collect();
        let advisories: String = self
            .profiles
            .iter()
            .filter(|p| !p.ran.advisories.is_empty())
            .map(|p| {
                let line = p.ran.advisories.line();
                format!("<li>{}: {}</li>\n", esc(&p.profile), esc(&line))
            })
            .collect();
        let not_served: String = self
            .not_served()
            .iter()
            .map(|line| format!("<li>{}</li>\n", esc(line)))
            .collect();
        let not_served = match not_served.is_empty() {
            true => String::new(),
            false => format!(
                "<h2>Not applicable: what the implementation declares it does not serve</h2>\n<ul id=\"not-served\">{not_served}</ul>\n"
            ),
        };
        let advisories = match advisories.is_empty() {
            true => String::new(),
            false => format!(
                "<h2>Advisories (allowed, never a verdict)</h2>\n<ul id=\"advisories\">{advisories}</ul>\n"
            ),
        };
        (problems, not_served, advisories)
    }

    /// Every check's row, and a section per failure with its diagram.
    fn checks_and_failures(&self) -> (String, String) {
        let mut failures = String::new();
        let mut checks = String::new();
        for p in &self.profiles {
            for (i, check) in p.ran.checks.iter().enumerate() {
                let label = check.result.kind().label();
                let cause = check.result.cause().unwrap_or_default();
                let _ = writeln!(
                    checks,
                    "<tr id=\"{}\" class=\"{label}\"><td>{}</td><td>{}</td><td>{label}</td><td>{}</td><td>{}</td></tr>",
                    anchor(&p.profile, i),
                    esc(&p.profile),
                    esc(&check.evidence.key()),
                    esc(&check.covers.join(", ")),
                    esc(cause)
                );
                let CheckResult::Fail(finding) = &check.result else {
                    continue;
                };
                let diagram = finding
                    .failure
                    .and_then(|n| p.ran.failures.get(n))
                    .map(|f| {
                        format!(
                            "<p>expected <code>{}</code><br>actual <code>{}</code></p>\n{}",
                            esc(&f.expected),
                            esc(&f.actual),
                            timing_diagram(f)
                        )
                    })
                    .unwrap_or_default();
                let _ = writeln!(
                    failures,
                    "<section class=\"failure\" id=\"failure-{}\"><h3>{} — {} ({})</h3>\n<p class=\"cause\">{}</p>\n{diagram}<pre>{}</pre></section>",
                    anchor(&p.profile, i),
                    esc(&p.profile),
                    esc(&check.evidence.key()),
                    esc(&finding.requirements.join(", ")),
                    esc(&finding.cause),
                    esc(&finding.details)
                );
            }
        }
        (checks, failures)
    }

    /// The errors grouped by cause, one item each.
    fn error_items(&self) -> String {
        self.errors_by_cause()
            .iter()
            .map(|(cause, list)| {
                format!(
                    "<li><b>{} check(s)</b>: {}<br><small>first: {}</small></li>\n",
                    list.len(),
                    esc(cause),
                    esc(&list[0])
                )
            })
            .collect()
    }
}

impl RunReport {
    /// The verdict table, one fold per catalogue area: the areas with a
    /// failure or an error first and open, in each the fail and error rows
    /// first and the others folded, every row with the requirement's text.
    fn verdicts_by_area(&self, catalogue: &Catalogue) -> String {
        const HEAD: &str = "<thead><tr><th>profile</th><th>requirement</th><th>verdict</th><th>statement</th><th>why</th><th>evidence</th></tr></thead>";
        let mut folds: Vec<(bool, String)> = Vec::new();
        for area in &catalogue.areas {
            let (mut problems, mut others) = (String::new(), String::new());
            let mut counts: BTreeMap<VerdictKind, usize> = BTreeMap::new();
            for p in &self.profiles {
                let index: BTreeMap<&Evidence, usize> = p
                    .ran
                    .checks
                    .iter()
                    .enumerate()
                    .map(|(i, c)| (&c.evidence, i))
                    .collect();
                for requirement in &area.requirements {
                    let Some(verdict) = p.verdicts.get(&requirement.id) else {
                        continue;
                    };
                    let evidence: Vec<String> = verdict
                        .evidence()
                        .into_iter()
                        .map(|e| match index.get(e) {
                            Some(i) => format!(
                                "<a href=\"#{}\">{}</a>",
                                anchor(&p.profile, *i),
                                esc(&e.key())
                            ),
                            None => esc(&e.key()),
                        })
                        .collect();
                    let why = match verdict {
                        Verdict::Pass(_) => String::new(),
                        _ => esc(&verdict.reason().unwrap_or_default()),
                    };
                    *counts.entry(verdict.kind()).or_default() += 1;
                    let problem = matches!(verdict.kind(), VerdictKind::Fail | VerdictKind::Error);
                    let _ = writeln!(
                        if problem { &mut problems } else { &mut others },
                        "<tr class=\"{}\"><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{why}</td><td class=\"evidence\">{}</td></tr>",
                        verdict.label().replace(' ', "-"),
                        esc(&p.profile),
                        requirement.id,
                        verdict.label(),
                        esc(&requirement.statement),
                        evidence.join("<br>")
                    );
                }
            }
            if counts.is_empty() {
                continue;
            }
            let counted: Vec<String> = VerdictKind::ALL
                .iter()
                .filter_map(|kind| {
                    let n = counts.get(kind)?;
                    let label = kind.label();
                    Some(format!(
                        "<span class=\"{}\">{n} {label}</span>",
                        label.replace(' ', "-")
                    ))
                })
                .collect();
            let has_problems = !problems.is_empty();
            let mut fold = format!(
                "<details class=\"area\"{}><summary>{} — {}: {}</summary>\n",
                if has_problems { " open" } else { "" },
                esc(&area.area),
                esc(&area.title),
                counted.join(", ")
            );
            if has_problems {
                let _ = writeln!(fold, "<table>{HEAD}<tbody>\n{problems}</tbody></table>");
            }
            if !others.is_empty() {
                let n = others.lines().count();
                let _ = writeln!(
                    fold,
                    "<details class=\"others\"><summary>{n} other verdicts (pass, not applicable, not run, not testable)</summary><table>{HEAD}<tbody>\n{others}</tbody></table></details>"
                );
            }
            fold.push_str("</details>\n");
            folds.push((has_problems, fold));
        }
        // Stable: the catalogue's order within each group.
        folds.sort_by_key(|(has_problems, _)| !*has_problems);
        folds.into_iter().map(|(_, fold)| fold).collect()
    }
}
