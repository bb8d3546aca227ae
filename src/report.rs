//! What a finished run tells its user: results, checks, the files it wrote, and the exit
//! code.

use grainflow::driver::RunHeader;
use grainflow::run::Status;

/// Print a run's results, checks, output folder with every file the run wrote, and any
/// error or restart hint; returns the exit code.
pub(crate) fn report(run: &RunHeader, out: &std::path::Path) -> i32 {
    if let Some(t) = run.settled_at_s {
        println!(
            "stopped early at t = {t:.4} s (step {}): the motion settled, its kinetic energy \
             below the scene's [run] stop threshold",
            run.steps
        );
    }
    for (k, v) in &run.results {
        println!("  {k} = {v:.6e}");
    }
    print_checks(&run.checks);
    for a in &run.analyses_skipped {
        let level = if run.shortened { "warning" } else { "error" };
        eprintln!("{level}: analysis `{}` skipped: {}", a.analysis, a.reason);
    }
    if run.shortened && !run.checks.is_empty() {
        eprintln!("note: --steps or --end-time cut the run short of the scene's length: its checks are reported, not judged");
    }
    println!("output: {}", out.display());
    println!("  wrote: {}", written_files(out));
    if let Some(e) = &run.error {
        eprintln!("error: {e}");
    }
    match run.status {
        Status::Ok => {}
        Status::ChecksFailed if !run.analyses_skipped.is_empty() => {
            eprintln!("error: an analysis the scene asks for could not run")
        }
        Status::ChecksFailed => eprintln!("error: at least one check failed"),
        Status::Unstable => eprintln!(
            "the output written so far is kept in {}, including the last good state",
            out.display()
        ),
        Status::Interrupted => eprintln!(
            "stopped by SIGTERM at step {}; continue with --restart {}",
            run.steps,
            out.join("checkpoint.h5").display()
        ),
    }
    exit_code(run.status)
}

/// The files this process wrote into `out` (modified since it started), by name, and the
/// pictures and movies under `pictures/` counted.
fn written_files(out: &std::path::Path) -> String {
    // A second's margin: file times come from a coarser clock than `now`.
    let since =
        *STARTED.get_or_init(std::time::SystemTime::now) - std::time::Duration::from_secs(1);
    let fresh = |dir: &std::path::Path| -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .into_iter()
            .flatten()
            .filter_map(Result::ok)
            .filter(|e| e.file_type().is_ok_and(|t| t.is_file()))
            .filter(|e| {
                e.metadata()
                    .and_then(|m| m.modified())
                    .is_ok_and(|t| t >= since)
            })
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .filter(|n| !n.starts_with('.'))
            .collect();
        names.sort();
        names
    };
    let mut list = fresh(out);
    let pictures = fresh(&out.join("pictures"));
    let png = pictures.iter().filter(|n| n.ends_with(".png")).count();
    let movies: Vec<&String> = pictures.iter().filter(|n| n.ends_with(".mp4")).collect();
    if png > 0 {
        list.push(format!("pictures/ ({png} PNG)"));
    }
    list.extend(movies.iter().map(|m| format!("pictures/{m}")));
    list.join(", ")
}

/// When this process started: files modified since were written by this run.
pub(crate) static STARTED: std::sync::OnceLock<std::time::SystemTime> = std::sync::OnceLock::new();

/// One line per check: PASS/FAIL (or SKIP, not judged, with what it would give), the
/// quantity, its value and the bounds.
fn print_checks(checks: &[grainflow::analysis::checks::CheckOutcome]) {
    for c in checks {
        let would = match (&c.skipped, c.value, c.passed) {
            (Some(_), Some(_), true) => " (would pass)",
            (Some(_), Some(_), false) => " (would fail)",
            _ => "",
        };
        println!(
            "  check {}: {} = {} -> {}{would}",
            match (&c.skipped, c.passed) {
                (Some(_), _) => "SKIP",
                (None, true) => "PASS",
                (None, false) => "FAIL",
            },
            c.quantity,
            c.value
                .map(|v| format!("{v:.6e}"))
                .unwrap_or_else(|| "missing".into()),
            describe_bounds(c)
        );
    }
}

/// Exit status: 0 ok, 2 a check failed, 3 unstable, 4 stopped by SIGTERM (checkpoint
/// written); 1 is any other error and [`crate::EXIT_USAGE`] a command line that did not parse.
pub(crate) fn exit_code(status: Status) -> i32 {
    match status {
        Status::Ok => 0,
        Status::ChecksFailed => 2,
        Status::Unstable => 3,
        Status::Interrupted => 4,
    }
}

fn describe_bounds(c: &grainflow::analysis::checks::CheckOutcome) -> String {
    let mut parts = Vec::new();
    if let Some(e) = c.expected {
        parts.push(format!("expected {e}"));
    }
    if let Some(t) = c.tolerance {
        parts.push(format!("± {t}"));
    }
    if let Some(t) = c.relative_tolerance {
        parts.push(format!("± {}%", t * 100.0));
    }
    if let Some(m) = c.min {
        parts.push(format!("≥ {m}"));
    }
    if let Some(m) = c.max {
        parts.push(format!("≤ {m}"));
    }
    parts.join(" ")
}
