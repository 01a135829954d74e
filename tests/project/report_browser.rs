//! The HTML report in a real browser: headless Chromium (Debian's `chromium`) loads
//! reports/<run>/index.html of a fresh `reproduce --tiny` run and the committed
//! reports/default/index.html; every image must load and no error may reach the console
//! (script errors, console.error, failed resource loads); every eye-view picture must have
//! pixel variance > 0 (read back through a canvas); a Summary and a table of contents come
//! before the first figure, no image is embedded twice, eye-view panels are labelled and no
//! literal Markdown backtick is left ([`assert_report`]). A screenshot is kept under the target
//! directory and its path printed. A control page with a missing image, a blank eye view
//! embedded twice without labels and a backtick must be reported (the check can fail). The
//! pictures of docs/ load too.
//!
//! Without chromium the test is skipped loudly — unless MOMENTLAB_REQUIRE_BROWSER=1 (set by
//! .ci/run when it installed chromium), where a missing browser is a failure.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

fn browser() -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    ["chromium", "chromium-browser"].iter().find_map(|name| {
        std::env::split_paths(&path)
            .map(|d| d.join(name))
            .find(|p| p.is_file())
    })
}

/// Installed first in <head>: records console.error calls, script errors, failed resource
/// loads (capture-phase error events) and unhandled rejections; after `load` it writes
/// {"images", "broken", "errors"} into <pre id="momentlab-check">.
const CHECKER: &str = r#"<script>
window.__momentlabErrors = [];
(function () {
  var errs = window.__momentlabErrors;
  var oe = console.error;
  console.error = function () {
    errs.push('console.error: ' + Array.prototype.join.call(arguments, ' '));
    return oe.apply(console, arguments);
  };
  window.addEventListener('error', function (e) {
    var t = e.target;
    if (t && t !== window && (t.src || t.href)) errs.push('failed to load ' + (t.src || t.href));
    else errs.push('script error: ' + e.message);
  }, true);
  window.addEventListener('unhandledrejection', function (e) { errs.push('unhandled rejection: ' + e.reason); });
  window.addEventListener('load', function () {
    var imgs = document.images, broken = [];
    for (var i = 0; i < imgs.length; i++) {
      if (!(imgs[i].complete && imgs[i].naturalWidth > 0)) broken.push(imgs[i].getAttribute('src'));
    }
    // Figures without a caption (an <img>/<svg> outside a <figure> with a <figcaption>, or a
    // caption that is only a file name), <pre> blocks holding Markdown tables, provenance.
    var uncaptioned = [];
    var figs = document.querySelectorAll('img, svg');
    for (var j = 0; j < figs.length; j++) {
      var f = figs[j].closest('figure');
      var c = f && f.querySelector('figcaption');
      var t = c ? c.textContent.trim() : '';
      if (!t || /^[\w.\/-]+\.(svg|png)$/.test(t)) uncaptioned.push(figs[j].getAttribute('src') || 'inline svg');
    }
    var mdpre = 0, pres = document.querySelectorAll('pre');
    for (var k = 0; k < pres.length; k++) {
      if (/^\s*\|.*\|\s*$/m.test(pres[k].textContent) && /\|\s*:?-{3,}/.test(pres[k].textContent)) mdpre++;
    }
    // Eye-view pictures (src under eye/): drawn into a canvas, variance of the pixel grey.
    var eye = [];
    for (var e = 0; e < imgs.length; e++) {
      var src = imgs[e].getAttribute('src') || '';
      if (!/(^|\/)eye\//.test(src)) continue;
      try {
        var cv = document.createElement('canvas');
        cv.width = imgs[e].naturalWidth; cv.height = imgs[e].naturalHeight;
        var g2 = cv.getContext('2d');
        g2.drawImage(imgs[e], 0, 0);
        var px = g2.getImageData(0, 0, cv.width, cv.height).data, n = 0, s1 = 0, s2 = 0;
        for (var q = 0; q < px.length; q += 4) {
          var y = (px[q] + px[q + 1] + px[q + 2]) / 3; s1 += y; s2 += y * y; n++;
        }
        var mean = n ? s1 / n : 0;
        eye.push({ src: src, pixels: n, variance: n ? s2 / n - mean * mean : 0 });
      } catch (err) { eye.push({ src: src, error: String(err) }); }
    }
    // The answers first: the Summary heading and the table of contents before the first figure.
    var firstFig = document.querySelector('figure');
    var h2s = document.querySelectorAll('h2'), summary = null;
    for (var h = 0; h < h2s.length; h++) if (h2s[h].textContent.trim() === 'Summary') { summary = h2s[h]; break; }
    var toc = document.querySelector('nav.toc');
    var before = function (a, b) { return !!a && (!b || (a.compareDocumentPosition(b) & 4) !== 0); };
    var tocLinks = toc ? toc.querySelectorAll("a[href^='#']") : [], deadLinks = 0;
    for (var t = 0; t < tocLinks.length; t++) if (!document.getElementById(tocLinks[t].getAttribute('href').slice(1))) deadLinks++;
    // Each image embedded once; eye views with a label per panel.
    var seenSrc = {}, twice = [], unlabelled = [];
    for (var d = 0; d < imgs.length; d++) {
      var s0 = imgs[d].getAttribute('src') || '';
      if (seenSrc[s0]) twice.push(s0); seenSrc[s0] = 1;
      if (/(^|\/)eye\//.test(s0)) {
        var fg = imgs[d].closest('figure');
        var labels = fg ? fg.querySelectorAll('.panel-labels span') : [];
        var named = 0;
        for (var q2 = 0; q2 < labels.length; q2++) if (labels[q2].textContent.trim()) named++;
        if (named !== 3) unlabelled.push(s0);
      }
    }
    // Markdown rendered: no literal backticks outside code.
    var bodyCopy = document.body.cloneNode(true);
    var codeEls = bodyCopy.querySelectorAll('pre, code, script');
    for (var c2 = 0; c2 < codeEls.length; c2++) codeEls[c2].remove();
    var backticks = (bodyCopy.textContent.match(/`/g) || []).length;
    var order = { summary_before_figure: before(summary, firstFig), toc_before_figure: before(toc, firstFig),
      toc_links: tocLinks.length, toc_dead_links: deadLinks, embedded_twice: twice,
      eye_unlabelled: unlabelled, backticks: backticks };
    var text = document.body.innerText;
    var provenance = ['git commit', 'command', 'CPU', 'threads', 'date (UTC)'].filter(function (w) { return text.indexOf(w) < 0; });
    var r = document.createElement('pre');
    r.id = 'momentlab-check';
    r.textContent = JSON.stringify({ images: imgs.length, broken: broken, errors: errs,
      uncaptioned: uncaptioned, markdown_pre: mdpre, provenance_missing: provenance, eye: eye, order: order });
    document.body.appendChild(r);
  });
})();
</script>"#;

fn chromium(bin: &Path, profile: &Path) -> Command {
    let mut c = Command::new(bin);
    c.args([
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-quic",
        "--no-first-run",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--hide-scrollbars",
        // file:// pictures may be read back through a canvas (the eye-view variance check)
        "--allow-file-access-from-files",
    ])
    .arg(format!("--user-data-dir={}", profile.display()));
    c
}

/// Load `page` (next to the report, so relative links resolve) and return the checker's result.
fn check_page(bin: &Path, profile: &Path, page: &Path) -> serde_json::Value {
    let url = format!("file://{}", page.display());
    let (code, out, err) = crate::common::run_limited(
        chromium(bin, profile)
            .arg("--virtual-time-budget=5000")
            .arg("--dump-dom")
            .arg(&url),
        None,
        Some(Duration::from_secs(90)),
    );
    assert_eq!(code, Some(0), "chromium --dump-dom failed: {err}");
    let start = out
        .find("<pre id=\"momentlab-check\">")
        .unwrap_or_else(|| panic!("{url}: the checker did not report (no load event?)\n{err}"));
    let body = &out[start + "<pre id=\"momentlab-check\">".len()..];
    let body = &body[..body.find("</pre>").unwrap()];
    let json = body
        .replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&quot;", "\"")
        .replace("&amp;", "&");
    serde_json::from_str(&json).unwrap_or_else(|e| panic!("{json}: {e}"))
}

fn with_checker(html: &str, extra_body: &str) -> String {
    let head = html.find("<head>").map(|i| i + "<head>".len()).unwrap_or(0);
    let mut s = format!("{}{CHECKER}{}", &html[..head], &html[head..]);
    if let Some(i) = s.rfind("</body>") {
        s.insert_str(i, extra_body);
    }
    s
}

#[test]
fn report_loads_in_headless_chromium() {
    let Some(bin) = browser() else {
        if std::env::var("MOMENTLAB_REQUIRE_BROWSER").as_deref() == Ok("1") {
            panic!("MOMENTLAB_REQUIRE_BROWSER=1 but no chromium on PATH");
        }
        eprintln!("SKIPPED report_loads_in_headless_chromium: chromium not installed (apt-get install chromium)");
        return;
    };
    let root = crate::common::tmp_path("browser");
    let out = crate::common::momentlab()
        .args(["reproduce", "--tiny", "--run", "b"])
        .arg("--out")
        .arg(root.join("reports"))
        .arg("--results")
        .arg(root.join("results"))
        .env("CI", "1")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let run = root.join("reports/b");
    let html = std::fs::read_to_string(run.join("index.html")).unwrap();
    let profile = root.join("profile");

    // The report: every image loads, nothing reaches the console, the answers come first.
    let page = run.join("index.check.html");
    std::fs::write(&page, with_checker(&html, "")).unwrap();
    let v = check_page(&bin, &profile, &page);
    assert_report(&v, &html, "reports/b of reproduce --tiny");

    // Control: a missing image, a console error and a blank eye view are caught.
    let blank = run.join("eye/blank_eye.png");
    {
        let f = std::io::BufWriter::new(std::fs::File::create(&blank).unwrap());
        let mut enc = png::Encoder::new(f, 8, 8);
        enc.set_color(png::ColorType::Rgb);
        let mut w = enc.write_header().unwrap();
        w.write_image_data(&[90u8; 8 * 8 * 3]).unwrap();
    }
    let control = run.join("index.control.html");
    std::fs::write(
        &control,
        with_checker(
            &html,
            "<img src=\"no-such-figure.svg\"><pre>| a | b |\n|---|---|\n| 1 | 2 |</pre>\
             <figure><img src=\"eye/blank_eye.png\"><figcaption>blank</figcaption></figure>\
             <figure><img src=\"eye/blank_eye.png\"><figcaption>blank again</figcaption></figure>\
             <p>a `literal` span</p>\
             <script>console.error('planted')</script>",
        ),
    )
    .unwrap();
    let c = check_page(&bin, &profile, &control);
    assert_eq!(
        c["broken"],
        serde_json::json!(["no-such-figure.svg"]),
        "{c}"
    );
    assert_eq!(
        c["uncaptioned"],
        serde_json::json!(["no-such-figure.svg"]),
        "{c}"
    );
    assert_eq!(c["markdown_pre"], serde_json::json!(1), "{c}");
    assert_eq!(
        c["order"]["embedded_twice"],
        serde_json::json!(["eye/blank_eye.png"]),
        "{c}"
    );
    assert!(
        c["order"]["eye_unlabelled"]
            .to_string()
            .contains("eye/blank_eye.png"),
        "{c}"
    );
    assert_eq!(c["order"]["backticks"], serde_json::json!(2), "{c}");
    let planted = c["eye"]
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["src"] == "eye/blank_eye.png")
        .cloned()
        .unwrap_or_else(|| panic!("blank eye view not checked: {c}"));
    assert_eq!(planted["pixels"], serde_json::json!(64), "{c}");
    assert_eq!(planted["variance"].as_f64(), Some(0.0), "{c}");
    let errs = c["errors"].to_string();
    assert!(
        errs.contains("no-such-figure.svg") && errs.contains("planted"),
        "{c}"
    );

    // Screenshot of the report as it renders, kept as an artefact.
    let shots = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("browser");
    std::fs::create_dir_all(&shots).unwrap();
    let shot = shots.join("report_tiny.png");
    let _ = std::fs::remove_file(&shot);
    let (code, _, err) = crate::common::run_limited(
        chromium(&bin, &profile)
            .arg("--window-size=1280,2400")
            .arg(format!("--screenshot={}", shot.display()))
            .arg(format!("file://{}", run.join("index.html").display())),
        None,
        Some(Duration::from_secs(90)),
    );
    assert_eq!(code, Some(0), "chromium --screenshot failed: {err}");
    let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&shot).unwrap()));
    let info = dec.read_info().unwrap().info().clone();
    assert_eq!((info.width, info.height), (1280, 2400));
    println!("screenshot: {}", shot.display());
    eprintln!("screenshot: {}", shot.display());
    std::fs::remove_dir_all(&root).ok();
}

/// What the browser must find in a report (`v` the checker's result on `html`): every image
/// loads, nothing reaches the console, every figure is captioned, no Markdown table is left as
/// text, provenance is on the first screen, every eye view is readable and not blank and PCF,
/// Hamburger 4MSM, TMSM, VSM and EVSM are seen from the eye; the answers first (a Summary and a
/// table of contents before the first figure), each image embedded once, eye-view panels
/// labelled, no literal Markdown backticks.
fn assert_report(v: &serde_json::Value, html: &str, what: &str) {
    let img_tags = html.matches("<img").count();
    assert!(
        img_tags >= 5,
        "{what}: only {img_tags} images in the report"
    );
    assert_eq!(v["images"].as_u64(), Some(img_tags as u64), "{what}: {v}");
    assert_eq!(
        v["broken"],
        serde_json::json!([]),
        "{what}: broken images: {v}"
    );
    assert_eq!(
        v["errors"],
        serde_json::json!([]),
        "{what}: console errors: {v}"
    );
    assert_eq!(
        v["uncaptioned"],
        serde_json::json!([]),
        "{what}: uncaptioned figures: {v}"
    );
    assert_eq!(
        v["markdown_pre"],
        serde_json::json!(0),
        "{what}: Markdown in <pre>: {v}"
    );
    assert_eq!(
        v["provenance_missing"],
        serde_json::json!([]),
        "{what}: provenance: {v}"
    );
    let eye = v["eye"].as_array().expect("eye list");
    for e in eye {
        assert!(
            e.get("error").is_none(),
            "{what}: eye view not readable: {e}"
        );
        assert!(
            e["pixels"].as_u64().unwrap_or(0) > 0,
            "{what}: empty eye view: {e}"
        );
        assert!(
            e["variance"].as_f64().unwrap_or(0.0) > 1.0,
            "{what}: blank eye view: {e}"
        );
    }
    for t in ["pcf", "hamburger4", "tmsm", "vsm", "evsm"] {
        let hit = eye.iter().any(|e| {
            e["src"]
                .as_str()
                .unwrap_or("")
                .ends_with(&format!("_{t}_eye.png"))
        });
        assert!(hit, "{what}: no eye view of {t}: {v}");
    }
    let o = &v["order"];
    assert_eq!(
        o["summary_before_figure"],
        serde_json::json!(true),
        "{what}: no Summary before the first figure: {o}"
    );
    assert_eq!(
        o["toc_before_figure"],
        serde_json::json!(true),
        "{what}: no table of contents before the first figure: {o}"
    );
    assert!(o["toc_links"].as_u64().unwrap_or(0) >= 5, "{what}: {o}");
    assert_eq!(o["toc_dead_links"], serde_json::json!(0), "{what}: {o}");
    assert_eq!(
        o["embedded_twice"],
        serde_json::json!([]),
        "{what}: images embedded twice: {o}"
    );
    assert_eq!(
        o["eye_unlabelled"],
        serde_json::json!([]),
        "{what}: eye views without panel labels: {o}"
    );
    assert_eq!(
        o["backticks"],
        serde_json::json!(0),
        "{what}: literal backticks: {o}"
    );
    // Provenance on the first screen: before the first figure and the first section.
    let prov = html.find("git commit").expect("no provenance");
    assert!(prov < html.find("<figure").unwrap_or(usize::MAX), "{what}");
    assert!(prov < html.find("<h2").unwrap_or(usize::MAX), "{what}");
    // Sub-reports are HTML: their tables are <table>s, not Markdown text.
    assert!(
        !html.contains("|---"),
        "{what}: Markdown table text in the HTML"
    );
}

/// The committed report, reports/default/index.html, passes the same checks as a fresh one:
/// loaded from a copy of its page outside the repository whose `<base>` is the committed
/// report's folder, so its relative links resolve to the committed files.
#[test]
fn committed_report_loads_in_headless_chromium() {
    let Some(bin) = browser() else {
        if std::env::var("MOMENTLAB_REQUIRE_BROWSER").as_deref() == Ok("1") {
            panic!("MOMENTLAB_REQUIRE_BROWSER=1 but no chromium on PATH");
        }
        eprintln!("SKIPPED committed_report_loads_in_headless_chromium: chromium not installed");
        return;
    };
    let run = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("reports/default");
    let html = std::fs::read_to_string(run.join("index.html")).unwrap();
    let root = crate::common::tmp_path("browser-committed");
    std::fs::create_dir_all(&root).unwrap();
    let page = root.join("index.check.html");
    let checked = with_checker(&html, "");
    let head = checked.find("<head>").map_or(0, |i| i + "<head>".len());
    let based = format!(
        "{}<base href=\"file://{}/\">{}",
        &checked[..head],
        run.display(),
        &checked[head..]
    );
    std::fs::write(&page, based).unwrap();
    let v = check_page(&bin, &root.join("profile"), &page);
    assert_report(&v, &html, "reports/default/index.html");
    std::fs::remove_dir_all(&root).ok();
}

/// The pictures of docs/ (docs/img/, generated from the pipeline's artefacts) load in the
/// browser, as the pages show them.
#[test]
fn docs_pictures_load_in_headless_chromium() {
    let Some(bin) = browser() else {
        if std::env::var("MOMENTLAB_REQUIRE_BROWSER").as_deref() == Ok("1") {
            panic!("MOMENTLAB_REQUIRE_BROWSER=1 but no chromium on PATH");
        }
        eprintln!("SKIPPED docs_pictures_load_in_headless_chromium: chromium not installed");
        return;
    };
    let docs = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("docs");
    let mut body = String::new();
    let mut n = 0;
    for (file, _) in momentlab::report::docs_figures::IMAGES {
        body.push_str(&format!(
            "<figure><img src=\"{file}\"><figcaption>the picture docs/{file} as a page of docs/ shows it</figcaption></figure>"
        ));
        n += 1;
    }
    let html = format!("<!DOCTYPE html><html><head></head><body>{body}</body></html>");
    let root = crate::common::tmp_path("browser-docs");
    std::fs::create_dir_all(&root).unwrap();
    // A copy of docs/img/ next to the page, so that the relative links are the pages' own.
    std::fs::create_dir_all(root.join("img")).unwrap();
    for (file, _) in momentlab::report::docs_figures::IMAGES {
        std::fs::copy(docs.join(file), root.join(file)).unwrap();
    }
    let page = root.join("docs.check.html");
    std::fs::write(&page, with_checker(&html, "")).unwrap();
    let v = check_page(&bin, &root.join("profile"), &page);
    assert!(n >= 6, "only {n} pictures in docs/");
    assert_eq!(v["images"].as_u64(), Some(n as u64), "{v}");
    assert_eq!(
        v["broken"],
        serde_json::json!([]),
        "broken pictures in docs/: {v}"
    );
    assert_eq!(v["errors"], serde_json::json!([]), "{v}");
}
