//! The eval's report as a person sees it: rendered by headless Chromium from disk (no server, no
//! network) in a 1280 × 800 window, its first screen holds the verdict and the summary table,
//! every image loads and no script or resource raises an error. Skipped, with a message, where
//! no Chromium is installed (`.ci/run` installs Debian's).

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The first Chromium on the PATH, if any.
fn chromium() -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    ["chromium", "chromium-browser", "google-chrome", "google-chrome-stable"]
        .iter()
        .flat_map(|name| std::env::split_paths(&path).map(move |dir| dir.join(name)))
        .find(|candidate| candidate.is_file())
}

/// What the page found about itself, written into the DOM once it has loaded and every image
/// was fetched again (so that lazily loaded pictures below the fold are checked too).
const PROBE: &str = r##"<script>
window.__problems = [];
window.addEventListener("error", function (event) {
  var target = event.target && (event.target.src || event.target.href);
  window.__problems.push("error: " + (event.message || target || "unknown"));
}, true);
(function () {
  var original = console.error;
  console.error = function () {
    window.__problems.push("console.error: " + Array.prototype.join.call(arguments, " "));
    original.apply(console, arguments);
  };
})();
window.addEventListener("load", function () {
  var images = Array.prototype.slice.call(document.images);
  Promise.all(images.map(function (img) {
    return new Promise(function (done) {
      var probe = new Image();
      probe.onload = function () { done(probe.naturalWidth > 0 ? null : img.getAttribute("src")); };
      probe.onerror = function () { done(img.getAttribute("src")); };
      probe.src = img.src;
    });
  })).then(function (broken) {
    var box = function (selector) {
      var element = document.querySelector(selector);
      if (!element) { return null; }
      var rect = element.getBoundingClientRect();
      return [rect.top, rect.bottom];
    };
    var out = document.createElement("pre");
    out.id = "browser-check";
    out.textContent = JSON.stringify({
      viewport: [window.innerWidth, window.innerHeight],
      verdict: box("#summary > p"),
      summary_table: box("#summary table"),
      images: images.length,
      broken: broken.filter(function (src) { return src !== null; }),
      problems: window.__problems,
      rows: document.querySelectorAll("#trials tr").length
    });
    document.body.appendChild(out);
  });
});
</script>"##;

/// Runs `chromium` on `page` and returns the DOM it dumps, or fails after two minutes.
fn render(chromium: &Path, page: &Path, profile: &Path) -> String {
    let mut child = Command::new(chromium)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--no-first-run",
            "--disable-extensions",
            "--allow-file-access-from-files",
            "--window-size=1280,800",
            "--virtual-time-budget=20000",
            "--dump-dom",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .arg(format!("file://{}", page.display()))
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("chromium starts");
    let started = Instant::now();
    loop {
        if child.try_wait().expect("chromium waits").is_some() {
            break;
        }
        if started.elapsed() > Duration::from_secs(120) {
            let _ = child.kill();
            panic!("chromium did not finish rendering {} in 120 s", page.display());
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    let output = child.wait_with_output().expect("chromium's output");
    String::from_utf8_lossy(&output.stdout).into_owned()
}

#[test]
fn the_report_opens_in_a_browser_on_its_verdict_with_every_image_and_no_error() {
    let Some(chromium) = chromium() else {
        eprintln!("skipped: no chromium on the PATH (Debian: apt-get install chromium); the report was not rendered");
        return;
    };
    let dir = std::env::temp_dir().join(format!("skillc-browser-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    let out = Command::new(env!("CARGO_BIN_EXE_skillc"))
        .args(["eval", "--skill", "touch", "--quiet", "--out"])
        .arg(dir.join("report"))
        .current_dir(root())
        .output()
        .expect("skillc runs");
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));

    // The probe goes first in <head>, so it hears the page's own scripts' errors.
    let html = std::fs::read_to_string(dir.join("report/index.html")).expect("index.html");
    let at = html.find("<head>").expect("a head") + "<head>".len();
    let probed = format!("{}{PROBE}{}", &html[..at], &html[at..]);
    let page = dir.join("report/probed.html");
    std::fs::write(&page, probed).expect("write the probed page");

    let dom = render(&chromium, &page, &dir.join("profile"));
    let start = dom.find("<pre id=\"browser-check\">").unwrap_or_else(|| {
        panic!(
            "the page did not finish its check; the DOM:\n{}",
            &dom[..dom.len().min(2000)]
        )
    }) + "<pre id=\"browser-check\">".len();
    let end = start + dom[start..].find("</pre>").expect("the check's end");
    let text = dom[start..end]
        .replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&amp;", "&");
    let check: serde_json::Value = serde_json::from_str(&text).expect("the check is JSON");

    let height = check["viewport"][1].as_f64().expect("viewport height");
    assert!(height >= 600.0, "a real window: {check}");
    for part in ["verdict", "summary_table"] {
        let top = check[part][0]
            .as_f64()
            .unwrap_or_else(|| panic!("{part} is on the page: {check}"));
        let bottom = check[part][1].as_f64().expect("bottom");
        assert!(
            top >= 0.0 && bottom <= height,
            "the {part} is on the first screen, without scrolling: {top}..{bottom} of {height} ({check})"
        );
    }
    // touch: its plots, and a 3-D picture of each of its trials.
    let images = check["images"].as_u64().expect("images");
    let trials = check["rows"].as_u64().expect("rows") - 1;
    assert!(images >= 4 + trials, "{images} images for {trials} trials: {check}");
    assert_eq!(check["broken"], serde_json::json!([]), "every image loads: {check}");
    assert_eq!(
        check["problems"],
        serde_json::json!([]),
        "no error in the console: {check}"
    );
    std::fs::remove_dir_all(&dir).expect("clean up");
}
