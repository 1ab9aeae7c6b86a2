//! End-to-end: `render` pictures, contact sheet and GIF; `view` pages checked in headless
//! Chromium (Debian's `chromium` package; `.ci/run` installs it and sets
//! `DIT_GARMENT_REQUIRE_BROWSER=1`, so there the browser check cannot be skipped).

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::{fails, ok};
use serde_json::Value;

/// A short recording of the default skirt on the walking default body.
fn recording(dir: &Path, name: &str, material: &str) -> PathBuf {
    let path = dir.join(name);
    ok(&[
        "simulate",
        "--motion",
        "walk:duration=1",
        "--frames",
        "10",
        "--blend-frames",
        "4",
        "--settle-frames",
        "1",
        "--material",
        material,
        "--out",
        path.to_str().unwrap(),
        "--quiet",
    ]);
    path
}

/// Pixels in the garment's blue and in the body's skin tone.
fn garment_and_body_pixels(image: &image::RgbImage) -> (usize, usize) {
    let mut counts = (0, 0);
    for p in image.pixels() {
        let [r, g, b] = p.0.map(i32::from);
        if b > r + 60 && b > g + 30 {
            counts.0 += 1;
        } else if r > b + 20 && r > 60 {
            counts.1 += 1;
        }
    }
    counts
}

#[test]
fn render_writes_pictures_a_sheet_a_gif_and_the_checked_json() {
    let dir = tempfile::tempdir().unwrap();
    let seq = recording(dir.path(), "a.mcap", "k_s=100");
    let out = dir.path().join("pictures");
    let report = dir.path().join("render.json");
    ok(&[
        "render",
        seq.to_str().unwrap(),
        "--frames",
        "0,9",
        "--views",
        "front,side",
        "--size",
        "160",
        "--gif",
        "--gif-size",
        "96",
        "--out",
        out.to_str().unwrap(),
        "--json",
        report.to_str().unwrap(),
    ]);
    let j: Value = serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    let images: Vec<PathBuf> = serde_json::from_value(j["images"].clone()).unwrap();
    assert_eq!(images.len(), 5, "4 pictures and the sheet: {images:?}");
    assert_eq!(images[0], out.join("frame_00000_front.png"));
    let first = image::open(&images[0]).unwrap().to_rgb8();
    assert_eq!(first.dimensions(), (160, 160));
    let (garment, body) = garment_and_body_pixels(&first);
    let reported = j["pixels_garment"].as_u64().unwrap() as usize;
    assert!(reported > 300, "the skirt covers {reported} pixels");
    // The reported count is the garment's coverage; shaded blue pixels are most of it.
    assert!(
        garment > reported / 2 && garment <= reported + 160,
        "{garment} blue pixels vs {reported} reported"
    );
    assert!(body > 500, "body pixels: {body}");
    let sheet = image::open(out.join("contact_sheet.png"))
        .unwrap()
        .to_rgb8();
    assert!(sheet.width() > 2 * 160 && sheet.height() > 2 * 160);
    let gif = std::fs::read(out.join("sequence.gif")).unwrap();
    assert!(gif.starts_with(b"GIF89a"), "not a GIF");

    // Colouring by the error against itself is all zero: every garment pixel is the scale's
    // low end (dark purple), with no blue base colour left.
    let coloured = dir.path().join("coloured");
    ok(&[
        "render",
        seq.to_str().unwrap(),
        "--frames",
        "9",
        "--size",
        "128",
        "--color-by",
        "error",
        "--against",
        seq.to_str().unwrap(),
        "--out",
        coloured.to_str().unwrap(),
    ]);
    let img = image::open(coloured.join("frame_00009_three-quarter.png"))
        .unwrap()
        .to_rgb8();
    let purple = img
        .pixels()
        .filter(|p| {
            let [r, g, b] = p.0.map(i32::from);
            b > g + 30 && r > g + 10
        })
        .count();
    assert!(purple > 100, "purple (zero error) pixels: {purple}");
    assert!(
        garment_and_body_pixels(&img).0 < purple,
        "the garment keeps its base colour"
    );
}

#[test]
fn simulate_foxglove_adds_a_scene_update_channel() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("fox.mcap");
    ok(&[
        "simulate",
        "--frames",
        "3",
        "--blend-frames",
        "2",
        "--settle-frames",
        "0",
        "--foxglove",
        "--out",
        path.to_str().unwrap(),
        "--quiet",
    ]);
    let bytes = std::fs::read(&path).unwrap();
    let recording = sim::recording::Recording::read(&path).unwrap();
    let (v, f) = (
        recording.template.positions.len(),
        recording.template.triangles.len(),
    );
    let mut scenes = 0;
    for message in mcap::MessageStream::new(&bytes).unwrap() {
        let m = message.unwrap();
        if m.channel.topic != "/foxglove/scene" {
            continue;
        }
        let schema = m.channel.schema.as_ref().expect("a schema");
        assert_eq!(schema.name, "foxglove.SceneUpdate");
        assert_eq!(schema.encoding, "jsonschema");
        assert_eq!(m.channel.message_encoding, "json");
        let scene: Value = serde_json::from_slice(&m.data).unwrap();
        let entities = scene["entities"].as_array().unwrap();
        assert_eq!(entities.len(), 2, "garment and body");
        let garment = &entities[0]["triangles"][0];
        assert_eq!(garment["points"].as_array().unwrap().len(), v);
        assert_eq!(garment["indices"].as_array().unwrap().len(), 3 * f);
        let body = &entities[1]["triangles"][0];
        let n = body["points"].as_array().unwrap().len();
        assert!(
            body["indices"]
                .as_array()
                .unwrap()
                .iter()
                .all(|i| i.as_u64().unwrap() < n as u64)
        );
        assert_eq!(entities[0]["timestamp"]["sec"], 0);
        scenes += 1;
    }
    assert_eq!(scenes, 3, "one scene per frame");
    // Off by default.
    let plain = dir.path().join("plain.mcap");
    ok(&[
        "simulate",
        "--frames",
        "2",
        "--blend-frames",
        "1",
        "--settle-frames",
        "0",
        "--out",
        plain.to_str().unwrap(),
        "--quiet",
    ]);
    let bytes = std::fs::read(&plain).unwrap();
    assert!(
        mcap::MessageStream::new(&bytes)
            .unwrap()
            .all(|m| m.unwrap().channel.topic != "/foxglove/scene")
    );
}

#[test]
fn render_and_view_refuse_bad_recordings_and_settings() {
    let dir = tempfile::tempdir().unwrap();
    let seq = recording(dir.path(), "a.mcap", "k_s=100");
    let bytes = std::fs::read(&seq).unwrap();
    let truncated = dir.path().join("truncated.mcap");
    std::fs::write(&truncated, &bytes[..bytes.len() / 2]).unwrap();
    let text = dir.path().join("text.mcap");
    std::fs::write(&text, "hello").unwrap();
    let out = dir.path().join("out");
    let page = dir.path().join("view.html");
    for bad in [&truncated, &text] {
        let err = fails(&[
            "render",
            bad.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(err.contains(bad.to_str().unwrap()), "{err}");
        let err = fails(&[
            "view",
            bad.to_str().unwrap(),
            "--out",
            page.to_str().unwrap(),
        ]);
        assert!(err.contains(bad.to_str().unwrap()), "{err}");
    }
    assert!(fails(&["render", truncated.to_str().unwrap(), "--out", "x"]).contains("truncated"));
    let s = seq.to_str().unwrap();
    let o = out.to_str().unwrap();
    assert!(fails(&["render", s, "--out", o, "--frames", "10"]).contains("past the end"));
    assert!(fails(&["render", s, "--out", o, "--views", "top"]).contains("unknown view"));
    assert!(fails(&["render", s, "--out", o, "--color-by", "error"]).contains("--against"));
    assert!(fails(&["render", s, "--out", o, "--range", "1,2"]).contains("--color-by"));
    assert!(
        !out.exists() && !page.exists(),
        "nothing written on failure"
    );
}

fn chromium() -> Option<PathBuf> {
    let candidates = [
        std::env::var_os("CHROMIUM").map(PathBuf::from),
        Some(PathBuf::from("/usr/bin/chromium")),
        Some(PathBuf::from("/usr/bin/chromium-browser")),
    ];
    candidates.into_iter().flatten().find(|p| p.exists())
}

/// Loads the page in headless Chromium (software WebGL) and returns the screenshot and the DOM.
fn browse(browser: &Path, page: &Path, work: &Path) -> (image::RgbImage, String) {
    let url = format!("file://{}#frame=9", page.display());
    let shot = work.join("shot.png");
    let _ = std::fs::remove_file(&shot);
    // One launch takes the screenshot and prints the page's DOM after its scripts ran.
    let out = Command::new("timeout")
        .arg("120")
        .arg(browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--use-angle=swiftshader",
            "--enable-unsafe-swiftshader",
            "--window-size=900,600",
            "--virtual-time-budget=20000",
            "--dump-dom",
        ])
        .arg(format!(
            "--user-data-dir={}",
            work.join("profile").display()
        ))
        .arg(format!("--screenshot={}", shot.display()))
        .arg(url)
        .output()
        .unwrap();
    assert!(
        shot.exists(),
        "no screenshot: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    (
        image::open(&shot).unwrap().to_rgb8(),
        String::from_utf8_lossy(&out.stdout).to_string(),
    )
}

#[test]
fn viewer_draws_the_garment_and_body_in_headless_chromium() {
    let browser = chromium();
    if !testkit::available(
        "pictures::viewer_draws_the_garment_and_body_in_headless_chromium",
        "BROWSER",
        browser.is_some(),
        "no chromium (apt-get install chromium, or set CHROMIUM)",
    ) {
        return;
    }
    let browser = browser.expect("checked above");
    let dir = tempfile::tempdir().unwrap();
    let a = recording(dir.path(), "a.mcap", "k_s=100");
    let b = recording(dir.path(), "b.mcap", "k_s=40,rho=0.5");
    let page = dir.path().join("view.html");
    ok(&["view", a.to_str().unwrap(), "--out", page.to_str().unwrap()]);
    let html = std::fs::read_to_string(&page).unwrap();
    assert!(
        !html.contains("http://") && !html.contains("https://"),
        "the page must not fetch anything"
    );
    let (shot, dom) = browse(&browser, &page, dir.path());
    assert!(
        dom.contains("viewer: ready"),
        "page did not finish: {dom:.2000}"
    );
    let (garment, body) = garment_and_body_pixels(&shot);
    assert!(
        garment > 3000,
        "garment pixels in the screenshot: {garment}"
    );
    assert!(body > 3000, "body pixels in the screenshot: {body}");

    // Two sequences side by side: the second garment is orange, in the right half.
    let pair = dir.path().join("pair.html");
    ok(&[
        "view",
        a.to_str().unwrap(),
        b.to_str().unwrap(),
        "--out",
        pair.to_str().unwrap(),
    ]);
    let (shot, dom) = browse(&browser, &pair, dir.path());
    assert!(dom.contains("viewer: ready") && dom.contains("k_s 40 N/m"));
    let half = shot.width() / 2;
    let (mut blue_left, mut orange_right) = (0, 0);
    for (x, _, p) in shot.enumerate_pixels() {
        let [r, g, b] = p.0.map(i32::from);
        if x < half && b > r + 60 && b > g + 30 {
            blue_left += 1;
        }
        if x >= half && r > b + 80 && g > b + 20 && r > g + 30 {
            orange_right += 1;
        }
    }
    assert!(blue_left > 1500, "first garment (left) pixels: {blue_left}");
    assert!(
        orange_right > 1500,
        "second garment (right) pixels: {orange_right}"
    );
}
