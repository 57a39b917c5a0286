//! The eval report: a terminal table, `summary.json` for machines, `index.html` with plots.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use super::real::RealResult;
use super::spark;
use super::tasks::{StepResult, TaskView};
use super::{Outcome, SkillView};
use skill_kit::atomic;
use skill_kit::plot::{self, Plot};
use skill_runtime::exec::RunLog;

fn percent(value: Option<f64>) -> String {
    value.map_or("-".to_string(), |v| format!("{:.1}", v * 100.0))
}

fn number(value: Option<f64>) -> String {
    value.map_or("-".to_string(), |v| format!("{v:.2}"))
}

/// The results as an aligned text table.
pub(super) fn table(outcomes: &[Outcome]) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{:<8} {:<31} {:<6} {:<4} {:>8} {:>9} {:>8} {:>7} {:>7}  why",
        "skill", "variant", "mode", "ok", "F rms %", "contact %", "peak N", "stop N", "time s"
    );
    for outcome in outcomes {
        let r = &outcome.result;
        let ok = if r.error {
            "ERR"
        } else if r.success {
            "yes"
        } else {
            "no"
        };
        let why = match (&r.reason, r.mode.as_str()) {
            (Some(reason), _) if !r.error => reason.as_str(),
            _ => "",
        };
        let _ = writeln!(
            out,
            "{:<8} {:<31} {:<6} {:<4} {:>8} {:>9} {:>8.1} {:>7} {:>7.2}  {why}",
            r.skill,
            truncate(&r.variant, 31),
            r.mode,
            ok,
            percent(r.force_rms_rel),
            percent(r.contact_share),
            r.peak_force_n,
            number(r.stop_force_n),
            r.duration_s
        );
        if r.error {
            let _ = writeln!(out, "         error: {}", r.message);
        }
        for step in &r.steps {
            let _ = writeln!(out, "{}", step_row(step));
        }
    }
    out
}

/// Whether a step row says yes, no or that it did not run (`-`); fallbacks are not judged.
fn step_ok(step: &StepResult) -> &'static str {
    if !step.ran {
        "-"
    } else if step.fallback {
        "fb"
    } else if step.success {
        "yes"
    } else {
        "no"
    }
}

/// One step of a task trial under its task's row: its metrics, the peak bound and why it failed.
fn step_row(step: &StepResult) -> String {
    let label = format!(
        "  {}step {} ({})",
        if step.fallback { "fallback " } else { "" },
        step.step,
        step.skill
    );
    let bound = step
        .peak_bound_n
        .map_or(String::new(), |bound| format!("peak bound {bound:.1} N"));
    let why = match (&step.reason, bound.is_empty()) {
        (Some(reason), true) => reason.clone(),
        (Some(reason), false) => format!("{reason}; {bound}"),
        (None, _) => bound,
    };
    format!(
        "{:<8} {:<31} {:<6} {:<4} {:>8} {:>9} {:>8.1} {:>7} {:>7.2}  {why}",
        "",
        truncate(&label, 31),
        "step",
        step_ok(step),
        percent(step.force_rms_rel),
        percent(step.contact_share),
        step.peak_force_n,
        number(step.stop_force_n),
        step.duration_s
    )
}

fn truncate(text: &str, width: usize) -> String {
    if text.chars().count() <= width {
        text.to_string()
    } else {
        let mut cut: String = text.chars().take(width - 1).collect();
        cut.push('…');
        cut
    }
}

pub(super) fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Writes `summary.json`, the plots and `index.html` into the folder `out` as a unit
/// ([`atomic::write_dir`]: an interrupted eval leaves the previous report or none); returns the
/// HTML's path.
pub(super) fn write(
    out: &Path,
    skills: &[SkillView<'_>],
    tasks: &[TaskView<'_>],
    outcomes: &[Outcome],
    elapsed_s: f64,
    table: &str,
    real: &[RealResult],
) -> std::io::Result<PathBuf> {
    atomic::write_dir(out, |dir| fill(dir, skills, tasks, outcomes, elapsed_s, table, real))?;
    Ok(out.join("index.html"))
}

/// [`write`]'s files, written into `out`.
fn fill(
    out: &Path,
    skills: &[SkillView<'_>],
    tasks: &[TaskView<'_>],
    outcomes: &[Outcome],
    elapsed_s: f64,
    table: &str,
    real: &[RealResult],
) -> std::io::Result<()> {
    std::fs::create_dir_all(out.join("plots"))?;
    let summary = serde_json::json!({
        "format_version": super::SUMMARY_VERSION,
        "elapsed_s": elapsed_s,
        "threads": rayon::current_num_threads(),
        "trials": outcomes.iter().map(|o| &o.result).collect::<Vec<_>>(),
        "real": real,
        "skills": skills.iter().map(|s| serde_json::json!({
            "name": s.name,
            "criteria": s.criteria,
            "error": s.error,
            "segments": s.bound.map(|b| &b.learned.segments),
        })).collect::<Vec<_>>(),
        "tasks": tasks.iter().map(|t| serde_json::json!({
            "name": t.name,
            "error": t.error,
            "replay": "none: a task has no replay baseline",
            "steps": t.steps.iter().map(|s| serde_json::json!({
                "step": s.step,
                "criteria": s.criteria,
                "demo": s.demo,
            })).collect::<Vec<_>>(),
        })).collect::<Vec<_>>(),
    });
    let json = serde_json::to_string_pretty(&summary).map_err(std::io::Error::other)? + "\n";
    atomic::write(&out.join("summary.json"), json.as_bytes())?;

    let mut html = String::new();
    html.push_str("<!doctype html>\n<html><head><meta charset=\"utf-8\"><title>skillc eval</title>\n<style>\n");
    html.push_str("body{font-family:sans-serif;margin:2em;max-width:1400px}table{border-collapse:collapse}td,th{border:1px solid #ccc;padding:3px 8px;text-align:right}td.l,th.l{text-align:left}.yes{background:#dfd}.no{background:#fdd}.err{background:#fb8}img{max-width:100%;border:1px solid #eee;margin:4px 0}.views{display:flex;flex-wrap:wrap;gap:6px}figure.view{margin:0;width:380px}figure.view img{width:100%;height:auto}pre{background:#f6f6f6;padding:1em}\n");
    html.push_str(".summary td,.summary th{font-size:1.05em}.failures li{margin:4px 0}input#filter{margin:8px 0;padding:4px;width:24em}th.sort{cursor:pointer}svg.spark{vertical-align:middle}.summary td{padding-top:1px;padding-bottom:1px}\n");
    html.push_str("</style></head><body>\n<h1>skillc eval</h1>\n");
    html.push_str(&first_screen(outcomes, skills, tasks));
    let _ = writeln!(
        html,
        "<p>{} trials in {elapsed_s:.1} s on {} worker threads. Each skill is learned once from its demonstration and reproduced in every variant of its scene; <em>replay</em> is the thesis's baseline (the learned motions under pure impedance control, no force control, no contact adaptation). A <em>task</em> runs its steps in sequence on one arm, each step learned once from its own demonstration and judged as a skill trial is, against its demonstration's peak force; tasks have no replay baseline.</p>",
        outcomes.len(),
        rayon::current_num_threads()
    );
    html.push_str("<h2 id=all>Every trial</h2>\n<input id=filter type=search placeholder=\"filter rows (skill, variant, mode, reason…)\" aria-label=\"filter rows\">\n");
    html.push_str("<table id=trials><tr><th class=l>skill</th><th class=l>variant</th><th class=l>mode</th><th>success</th><th>force RMS / learned %</th><th>contact %</th><th>peak N</th><th>stop N</th><th>learned N</th><th>goal error mm</th><th>time s</th><th class=l>message</th></tr>\n");
    for outcome in outcomes {
        let r = &outcome.result;
        let class = if r.error {
            "err"
        } else if r.success {
            "yes"
        } else {
            "no"
        };
        let _ = writeln!(
            html,
            "<tr class={class}><td class=l>{}</td><td class=l>{}</td><td class=l>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{:.1}</td><td>{}</td><td>{}</td><td>{:.1}</td><td>{:.2}</td><td class=l>{}</td></tr>",
            escape(&r.skill),
            escape(&r.variant),
            r.mode,
            if r.error { "error" } else if r.success { "yes" } else { "no" },
            percent(r.force_rms_rel),
            percent(r.contact_share),
            r.peak_force_n,
            number(r.stop_force_n),
            number(r.learned_force_n),
            r.goal_error_m * 1e3,
            r.duration_s,
            escape(&r.message)
        );
        for step in &r.steps {
            let class = match step_ok(step) {
                "yes" => "yes",
                "no" => "no",
                _ => "",
            };
            let _ = writeln!(
                html,
                "<tr class=\"{class}\"><td class=l></td><td class=l>{}step {} ({})</td><td class=l>step</td><td>{}</td><td>{}</td><td>{}</td><td>{:.1} (bound {})</td><td>{}</td><td>{}</td><td></td><td>{:.2}</td><td class=l>{}{}</td></tr>",
                if step.fallback { "fallback " } else { "" },
                escape(&step.step),
                escape(&step.skill),
                step_ok(step),
                percent(step.force_rms_rel),
                percent(step.contact_share),
                step.peak_force_n,
                number(step.peak_bound_n),
                number(step.stop_force_n),
                number(step.learned_force_n),
                step.duration_s,
                step.reason.as_deref().map_or(String::new(), |reason| format!("{}: ", escape(reason))),
                escape(&step.message)
            );
        }
    }
    html.push_str("</table>\n");
    html.push_str(TABLE_SCRIPT);
    for skill in skills {
        let _ = writeln!(html, "<h2 id=\"{}\">{}</h2>", anchor(skill.name), escape(skill.name));
        if let Some(error) = skill.error {
            let _ = writeln!(html, "<p class=err>could not learn: {}</p>", escape(error));
            continue;
        }
        let _ = writeln!(
            html,
            "<p>criteria: {}</p>",
            escape(&serde_json::to_string(&skill.criteria).unwrap_or_default())
        );
        let runs: Vec<plot::Trial<'_>> = outcomes
            .iter()
            .filter(|o| o.result.skill == skill.name && o.result.mode != "task")
            .map(Outcome::trial)
            .collect();
        for (plot, caption) in [
            (Plot::Trajectory, "Tool path: demonstration (coloured by segment), learned rollout, every reproduction (solid: skill, dashed: replay), compliant-frame z axes as arrows."),
            (Plot::Force, "Applied force along the compliant z during the trial (solid: skill, dashed: replay) and the learned desired force (black)."),
            (Plot::WorldForce, "Applied force in the world frame, demonstration and skill trial as demonstrated."),
            (Plot::Timeline, "States over time, per trial."),
        ] {
            let kind = plot.name();
            let file = format!("{}_{kind}.svg", skill.name);
            match plot::draw(plot, &out.join("plots").join(&file), &skill.subject(), &runs) {
                Ok(()) => {
                    let _ = writeln!(html, "<figure><img src=\"plots/{file}\" alt=\"{kind}\"><figcaption>{caption}</figcaption></figure>");
                }
                Err(err) => {
                    let _ = writeln!(html, "<p class=err>plot {kind} failed: {}</p>", escape(&err));
                }
            }
        }
        let trials: Vec<&Outcome> = outcomes
            .iter()
            .filter(|o| o.result.skill == skill.name && o.result.mode != "task")
            .collect();
        trial_views(&mut html, out, skill.name, &trials);
    }
    for task in tasks {
        let _ = writeln!(
            html,
            "<h2 id=\"{}\">task {}</h2>\n<p>No replay baseline: a task's steps start where the last ended (and `at:` where an earlier step found a state), which a replay of each demonstration cannot do.</p>",
            anchor(task.name),
            escape(task.name)
        );
        if let Some(error) = task.error {
            let _ = writeln!(html, "<p class=err>could not prepare: {}</p>", escape(error));
            continue;
        }
        let trials: Vec<&Outcome> = outcomes
            .iter()
            .filter(|o| o.result.skill == task.name && o.result.mode == "task")
            .collect();
        for (index, step) in task.steps.iter().enumerate() {
            let _ = writeln!(
                html,
                "<h3>step {}</h3>\n<p>criteria: {}</p>",
                escape(step.step),
                escape(&serde_json::to_string(&step.criteria).unwrap_or_default())
            );
            let runs: Vec<plot::Trial<'_>> = trials
                .iter()
                .filter_map(|o| {
                    o.step_logs.get(index).map(|log| plot::Trial {
                        variant: &o.result.variant,
                        replay: false,
                        error: o.result.error || log.ticks.is_empty(),
                        log,
                    })
                })
                .collect();
            let subject = plot::Subject {
                name: &step.title,
                demo: step.demo,
                bound: step.bound.as_ref(),
            };
            for (plot, caption) in [
                (Plot::Force, "Applied force along the compliant z during the step, per variant, and the learned desired force (black)."),
                (Plot::Timeline, "The step's states over time, per variant."),
            ] {
                let kind = plot.name();
                let file = format!("{}_{kind}.svg", step.title);
                match plot::draw(plot, &out.join("plots").join(&file), &subject, &runs) {
                    Ok(()) => {
                        let _ = writeln!(html, "<figure><img src=\"plots/{file}\" alt=\"{kind}\"><figcaption>{caption}</figcaption></figure>");
                    }
                    Err(err) => {
                        let _ = writeln!(html, "<p class=err>plot {kind} failed: {}</p>", escape(&err));
                    }
                }
            }
        }
        trial_views(&mut html, out, task.name, &trials);
    }
    if !real.is_empty() {
        html.push_str("<h2>Real demonstrations</h2>\n<p>The wipe template (approach, strokes in contact, retreat) learned from each real demonstration; boundary errors are the distance from each of the authors' label boundaries to the nearest boundary found.</p>\n");
        let _ = writeln!(html, "<pre>{}</pre>", escape(&real_table(real)));
    }
    let _ = writeln!(
        html,
        "<h2>Terminal table</h2>\n<pre>{}</pre>\n</body></html>",
        escape(table)
    );
    atomic::write(&out.join("index.html"), html.as_bytes())
}

/// The report's first screen: whether it worked. One line per skill and task (trials passed of
/// those run, the worst force error, the worst peak against its bound), then every failed trial
/// with its reason in words and a link to its plots; the full table follows further down.
fn first_screen(outcomes: &[Outcome], skills: &[SkillView<'_>], tasks: &[TaskView<'_>]) -> String {
    let judged = |o: &&Outcome| o.result.mode == "skill" || o.result.mode == "task";
    let failed: Vec<&Outcome> = outcomes
        .iter()
        .filter(judged)
        .filter(|o| o.result.error || !o.result.success)
        .collect();
    let run = outcomes.iter().filter(judged).count();
    let mut html = String::new();
    let verdict = if failed.is_empty() {
        format!("<p class=yes style=\"padding:6px\"><strong>All {run} skill and task trials pass.</strong> (Replay baselines are reported but not judged.)</p>")
    } else {
        format!(
            "<p class=no style=\"padding:6px\"><strong>{} of {run} skill and task trials fail.</strong> They are listed first below.</p>",
            failed.len()
        )
    };
    html.push_str("<section id=summary>\n");
    html.push_str(&verdict);
    html.push_str("<table class=summary><tr><th class=l>skill or task</th><th>passed / run</th><th>worst force RMS %</th><th>worst peak N (its bound)</th><th class=l>worst trial: force along z (blue) against its target (dashed)</th><th class=l>plots</th></tr>\n");
    let names = skills
        .iter()
        .map(|s| (s.name, "skill"))
        .chain(tasks.iter().map(|t| (t.name, "task")));
    let mut rows: Vec<(bool, String)> = Vec::new();
    for (name, mode) in names {
        let trials: Vec<&Outcome> = outcomes
            .iter()
            .filter(|o| o.result.skill == name && o.result.mode == mode)
            .collect();
        let passed = trials.iter().filter(|o| o.result.success && !o.result.error).count();
        let worst_rms = trials.iter().filter_map(|o| o.result.force_rms_rel).reduce(f64::max);
        // The worst peak is the one nearest its bound (or furthest past it).
        let worst_peak = trials
            .iter()
            .map(|o| (o.result.peak_force_n, o.result.peak_bound_n))
            .max_by(|a, b| {
                let share = |(peak, bound): (f64, Option<f64>)| bound.map_or(0.0, |b| peak / b.max(1e-9));
                share(*a).total_cmp(&share(*b))
            });
        let peak = worst_peak.map_or("-".to_string(), |(peak, bound)| match bound {
            Some(bound) => format!("{peak:.1} ({bound:.1})"),
            None => format!("{peak:.1}"),
        });
        let ok = passed == trials.len() && !trials.is_empty();
        let chart = spark::worst(&trials).map_or(String::new(), |worst| {
            format!(
                "{} <small>{}{}</small>",
                spark::chart(worst),
                escape(&worst.result.variant),
                worst
                    .result
                    .reason
                    .as_deref()
                    .map_or(String::new(), |reason| format!(": {}", escape(reason)))
            )
        });
        rows.push((
            ok,
            format!(
                "<tr class={}><td class=l>{}{}</td><td>{passed} / {}</td><td>{}</td><td>{peak}</td><td class=l>{chart}</td><td class=l><a href=\"#{}\">plots</a></td></tr>\n",
                if ok { "yes" } else { "no" },
                if mode == "task" { "task " } else { "" },
                escape(name),
                trials.len(),
                percent(worst_rms),
                anchor(name)
            ),
        ));
    }
    // Failures first.
    rows.sort_by_key(|(ok, _)| *ok);
    for (_, row) in rows {
        html.push_str(&row);
    }
    html.push_str("</table>\n");
    if !failed.is_empty() {
        html.push_str("<h2>Failed trials</h2>\n<ul class=failures>\n");
        for o in &failed {
            let r = &o.result;
            let _ = writeln!(
                html,
                "<li><a href=\"#{}\">{} — {}</a> ({}): {}</li>",
                anchor(&r.skill),
                escape(&r.skill),
                escape(&r.variant),
                r.reason.as_deref().map_or("error".to_string(), escape),
                escape(&r.message)
            );
        }
        html.push_str("</ul>\n");
    }
    html.push_str("<p><a href=\"#all\">Every trial</a> (a table that sorts by a column when its heading is clicked and filters as you type) follows, then each skill's and task's plots.</p>\n</section>\n");
    html
}

/// An HTML id for a skill or task name (letters, digits, `-` and `_` kept).
fn anchor(name: &str) -> String {
    format!("trial-{}", safe_name(name))
}

/// `name` with every character but letters, digits, `-` and `_` made a `-`: an HTML id's or a
/// file name's part.
fn safe_name(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '-'
            }
        })
        .collect()
}

/// Each trial of `trials` in 3-D (the tool's path over its scene, contact coloured by force),
/// as a grid of pictures; a trial that did not run is left out.
fn trial_views(html: &mut String, out: &Path, name: &str, trials: &[&Outcome]) {
    let drawn: Vec<String> = trials
        .iter()
        .filter(|o| !o.result.error)
        .map(|o| {
            let r = &o.result;
            let logs: Vec<&RunLog> = if o.step_logs.is_empty() {
                vec![&o.log]
            } else {
                o.step_logs.iter().collect()
            };
            let file = format!("{}_{}_{}_3d.svg", safe_name(name), safe_name(&r.variant), r.mode);
            let verdict = if r.success { "success" } else { "failure" };
            let title = format!("{} · {} · {} · {verdict}", r.skill, r.variant, r.mode);
            match skill_kit::scene_view::draw(&out.join("plots").join(&file), &title, &logs, &o.objects) {
                Ok(()) => format!(
                    "<figure class=view><img src=\"plots/{file}\" alt=\"{} {} in 3-D\" loading=lazy width=560 height=440><figcaption class={}>{} {}: {verdict}</figcaption></figure>",
                    escape(&r.variant),
                    r.mode,
                    if r.success { "yes" } else { "no" },
                    escape(&r.variant),
                    r.mode
                ),
                Err(err) => format!("<p class=err>3-D picture of {} failed: {}</p>", escape(&r.variant), escape(&err)),
            }
        })
        .collect();
    if drawn.is_empty() {
        return;
    }
    let _ = writeln!(
        html,
        "<details open><summary>Each trial in 3-D: the tool's path (grey line, green dot: start, cross: end) over the scene's objects (grey faces, cut where the view ends), contact points coloured by the force, one metre as long on every axis, z up</summary>\n<div class=views>{}</div></details>",
        drawn.join("\n")
    );
}

/// A few lines of plain script: click a heading to sort the table by it, type to filter rows.
/// The table reads the same without it.
const TABLE_SCRIPT: &str = r#"<script>
(function () {
  var table = document.getElementById("trials");
  var filter = document.getElementById("filter");
  if (!table || !filter) { return; }
  var head = table.rows[0];
  var body = Array.prototype.slice.call(table.rows, 1);
  filter.addEventListener("input", function () {
    var needle = filter.value.toLowerCase();
    body.forEach(function (row) {
      row.style.display = row.textContent.toLowerCase().indexOf(needle) >= 0 ? "" : "none";
    });
  });
  Array.prototype.forEach.call(head.cells, function (cell, column) {
    cell.className += " sort";
    cell.title = "sort by this column";
    var ascending = true;
    cell.addEventListener("click", function () {
      var key = function (row) {
        var text = row.cells[column] ? row.cells[column].textContent : "";
        var number = parseFloat(text);
        return isNaN(number) ? text : number;
      };
      body.sort(function (a, b) {
        var x = key(a), y = key(b);
        var order = (typeof x === typeof y) ? (x < y ? -1 : x > y ? 1 : 0) : (typeof x === "number" ? -1 : 1);
        return ascending ? order : -order;
      });
      ascending = !ascending;
      body.forEach(function (row) { table.tBodies[0].appendChild(row); });
    });
  });
})();
</script>
"#;

/// The real-demonstration results as text.
pub(super) fn real_table(results: &[RealResult]) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "real demonstrations (wipe template):");
    for r in results {
        if let Some(why) = &r.skipped {
            let _ = writeln!(out, "  {:<14} {why}", r.file);
            continue;
        }
        let errors: Vec<String> = r.boundary_errors_s.iter().map(|e| format!("{e:.2}")).collect();
        let found: Vec<String> = r.found_boundaries_s.iter().map(|e| format!("{e:.2}")).collect();
        let labels: Vec<String> = r.label_boundaries_s.iter().map(|e| format!("{e:.2}")).collect();
        let _ = writeln!(
            out,
            "  {:<14} boundaries found [{}] s, labelled [{}] s, errors [{}] s; force {} N; {} strokes; reproduction: {} (force RMS {}%, contact {}%, peak {})",
            r.file,
            found.join(", "),
            labels.join(", "),
            errors.join(", "),
            number(r.force_n),
            r.strokes.map_or("no".to_string(), |n| n.to_string()),
            r.reproduction.as_deref().unwrap_or("-"),
            percent(r.force_rms_rel),
            percent(r.contact_share),
            r.peak_force_n
                .map_or("-".to_string(), |[peak, bound]| format!("{peak:.1} N of {bound:.1} N"))
        );
        let _ = writeln!(out, "  {:<14} {}", "", r.learning_line());
        if let Some(wrench) = &r.wrench {
            let _ = writeln!(out, "  {:<14} {wrench}", "");
        }
    }
    out
}
