//! `engine --scene glass` end to end, on a small copy of the glass scene:
//! the first run traces the room shell map, solves the per-sample shell
//! maps and plays hybrid frames (the default mode for glass) with
//! validation clean; later runs compile nothing; a damaged per-sample map
//! is solved again; a bad τ and hybrid without glass fail cleanly; an
//! object near the glass plays as a layer of its own, traced once.

mod common;

use common::glass_cli::*;
use common::run_engine as engine;
use std::path::Path;

/// glass.toml with a 16² shell map, a coarse teapot and per-sample shell
/// maps at orbit lines 0, 50 and 99 (one view each), in `dir`.
fn small_glass(dir: &Path) -> String {
    small_scene(
        dir,
        "glass",
        &[
            ("shell_every = 10", "shell_every = 50"),
            ("views = 3", "views = 1"),
        ],
    )
}

#[test]
fn glass_compiles_its_shell_once_and_plays_hybrid() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scene = small_glass(dir.path());
    let out = dir.path().join("out");
    let stderr = run_clean(&scene, &out, &[]);
    assert!(stderr.contains("traced the room shell map"), "{stderr}");
    assert!(
        stderr.contains("solved 3 per-sample shell maps"),
        "{stderr}"
    );
    assert!(
        stderr.contains("compressed 3 per-sample shell maps"),
        "{stderr}"
    );
    assert!(out.join("glass/room_shells.ptxc").is_file());
    assert!(out.join("glass/room_shell.bin").is_file());
    // The room around the glass is drawn from its inferred light maps, as
    // in the reflector modes (it was the analytic room).
    assert!(stderr.contains("room light maps compiled"), "{stderr}");
    assert!(out.join("room/floor.light.exr").is_file());
    for line in ["0000", "0050", "0099"] {
        assert!(
            out.join(format!("glass/room_shell_line{line}.bin"))
                .is_file()
        );
    }
    // Per-sample maps composite deferred: the lens into its G-buffer
    // first (its depth spares the room's shading behind it), then each of
    // its pixels once over the room.
    assert_eq!(
        pass_names(&out),
        ["glass_gbuffer", "room", "glass", "readback"]
    );

    // Cached: nothing traced again; the baseline plays from the same map.
    let stderr = run_clean(&scene, &out, &["--mode", "static-em", "--tau", "10"]);
    assert!(!stderr.contains("traced the room shell map"), "{stderr}");
    assert!(!stderr.contains("per-sample"), "{stderr}");

    // A damaged container is compressed again from the maps; a damaged
    // map, played as solved (`--maps exr`), is solved again (that one
    // only); the traced shell alone plays without them.
    std::fs::write(out.join("glass/room_shells.ptxc"), b"not a container").expect("damage");
    let stderr = run_clean(&scene, &out, &["--compositing", "multipass"]);
    assert!(
        stderr.contains("compressed 3 per-sample shell maps"),
        "{stderr}"
    );
    // The forward pass, as the papers draw it.
    assert_eq!(pass_names(&out), ["room", "glass", "readback"]);
    assert!(!stderr.contains("solved"), "{stderr}");
    let damaged = out.join("glass/room_shell_line0050.bin");
    std::fs::write(&damaged, b"not a map").expect("damage a map");
    let stderr = run_clean(&scene, &out, &["--maps", "exr"]);
    assert!(
        stderr.contains("solved 1 per-sample shell maps"),
        "{stderr}"
    );
    assert_glass_bench(&scene, &out);
    let traced = run(&scene, &out, &["--traced-shell"]);
    let stderr = String::from_utf8_lossy(&traced.stderr);
    assert!(traced.status.success(), "stderr:\n{stderr}");
    assert!(!stderr.contains("per-sample"), "{stderr}");
    eval_states_the_shells(&scene, &out, dir.path());

    let bad_tau = run(&scene, &out, &["--tau", "0"]);
    let stderr = String::from_utf8_lossy(&bad_tau.stderr);
    assert!(
        !bad_tau.status.success() && !stderr.contains("panicked"),
        "{stderr}"
    );
    assert!(
        stderr
            .lines()
            .any(|l| l.starts_with("error:") && l.contains("'0' for '--tau")),
        "{stderr}"
    );
}

/// `engine bench` on a glass scene (its maps compiled under `out`) times
/// the glass rows, validation-clean, each hybrid row with its glass passes.
fn assert_glass_bench(scene: &str, out: &Path) {
    let o = engine(&[
        "bench",
        "--scene",
        scene,
        "--size",
        "96x64",
        "--frames",
        "1",
        "--warmup",
        "1",
        "--out",
        out.to_str().expect("utf-8 path"),
        "--validate",
    ]);
    let log = String::from_utf8_lossy(&o.stderr).into_owned() + &String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{log}");
    assert!(!log.contains("solved"), "{log}");
    let bench: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("bench.json")).expect("bench.json"))
            .expect("valid JSON");
    assert_eq!(bench["kind"], "glass", "{bench}");
    let rows = bench["rows"].as_array().expect("rows");
    let names: Vec<&str> = rows.iter().filter_map(|r| r["name"].as_str()).collect();
    assert_eq!(
        names,
        [
            "bare",
            "static-em",
            "hybrid, tau 3",
            "hybrid, tau 5",
            "hybrid, tau 10",
            "hybrid, tau 10, multipass",
            "hybrid, tau 10, traced shell"
        ]
    );
    for r in rows {
        assert!(
            r["frame_ms_median"].as_f64().is_some_and(|v| v > 0.0),
            "{r}"
        );
        let glass = r["glass_ms_median"].as_f64();
        assert_eq!(glass.is_some(), r["name"] != "bare", "{r}");
    }
    // Each row drew what it says: the deferred rows a G-buffer, the
    // forward and traced-shell rows none.
    let passes = |i: usize| -> Vec<&str> {
        (rows[i]["report"]["passes"]
            .as_array()
            .expect("passes")
            .iter())
        .filter_map(|p| p["name"].as_str())
        .collect()
    };
    assert!(passes(4).contains(&"glass_gbuffer"), "{:?}", passes(4));
    assert!(!passes(5).contains(&"glass_gbuffer"), "{:?}", passes(5));
    assert!(!passes(6).contains(&"glass_gbuffer"), "{:?}", passes(6));
    assert!(log.contains("glass ms"), "{log}");
    assert!(bench.get("covered_pixels").is_none(), "{bench}");
    // Where each row's frame goes, as a picture: a bar per row.
    let chart = image::open(out.join("bench.png")).expect("bench.png");
    assert!(
        chart.height() >= 120 + 34 * rows.len() as u32,
        "{}",
        chart.height()
    );
    // The rows set τ and the shells themselves: flags that would are refused.
    let flagged = engine(&[
        "bench",
        "--scene",
        scene,
        "--tau",
        "5",
        "--traced-shell",
        "--out",
        out.to_str().expect("utf-8 path"),
    ]);
    let stderr = String::from_utf8_lossy(&flagged.stderr);
    assert!(
        !flagged.status.success() && !stderr.contains("panicked"),
        "{stderr}"
    );
    assert!(
        stderr
            .lines()
            .any(|l| l.starts_with("error:") && l.contains("--tau, --traced-shell")),
        "{stderr}"
    );
}

/// The passes `out/perf.json` times, in order (a hybrid run's).
fn pass_names(out: &Path) -> Vec<String> {
    let perf: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("perf.json")).expect("perf.json"))
            .expect("valid JSON");
    assert_eq!(perf["mode"], "Hybrid");
    (perf["passes"].as_array().expect("passes").iter())
        .filter_map(|p| p["name"].as_str().map(String::from))
        .collect()
}

/// `engine compile` on a glass scene solves its per-sample shell maps
/// without playing and ships their container with its key; a second
/// compile solves nothing; shards and a scene without per-sample maps
/// fail cleanly.
#[test]
fn a_glass_scene_compiles_and_ships_its_shell_maps() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scene = small_glass(dir.path());
    let (out, dest) = (dir.path().join("out"), dir.path().join("ship"));
    let compile = |extra: &[&str]| compile(&scene, &out, extra);
    let o = compile(&["--ship", dest.to_str().expect("utf-8 path")]);
    let log = common::output_text(&o);
    assert!(o.status.success(), "{log}");
    assert!(log.contains("solved 3 per-sample shell maps"), "{log}");
    assert!(log.contains("shipped"), "{log}");
    let shipped = dest.join("glass/room_shells.ptxc");
    assert_eq!(
        std::fs::read(&shipped).expect("shipped container"),
        std::fs::read(out.join("glass/room_shells.ptxc")).expect("compiled container")
    );
    assert!(inference::key::is_ours(&shipped), "shipped with its key");
    // The room's light maps ship beside it.
    assert!(log.contains("room light maps compiled"), "{log}");
    let light = dest.join("room/floor.light.exr");
    assert!(
        inference::key::is_ours(&light),
        "light map shipped with its key"
    );

    let again = compile(&[]);
    let stderr = String::from_utf8_lossy(&again.stderr);
    assert!(again.status.success(), "{stderr}");
    assert!(!stderr.contains("solved"), "{stderr}");
    let shard = compile(&["--shard", "1/2"]);
    let stderr = String::from_utf8_lossy(&shard.stderr);
    assert!(
        !shard.status.success() && stderr.contains("one part"),
        "{stderr}"
    );

    let plain = small_scene(
        dir.path(),
        "glass",
        &[("shell_every = 10", "shell_every = 0")],
    );
    let o = engine(&[
        "compile",
        "--scene",
        &plain,
        "--out",
        out.to_str().expect("utf-8"),
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && !stderr.contains("panicked"),
        "{stderr}"
    );
    assert!(stderr.contains("nothing to compile"), "{stderr}");
}

/// The shipped glass scene's first run from an empty `--out` plays the
/// per-sample shell maps shipped in `assets/compiled/glass` (keys match)
/// instead of solving them for minutes; `--recompile` would solve them.
#[test]
fn the_shipped_glass_scene_plays_its_shipped_shell_maps() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("out");
    let out = out.to_str().expect("utf-8 path");
    let o = engine(&[
        "--scene",
        "glass",
        "--out",
        out,
        "--frames",
        "1",
        "--warmup",
        "0",
        "--tau",
        "10",
        "--no-capture",
        "--validate",
    ]);
    let (stdout, stderr) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr),
    );
    assert!(o.status.success(), "{stderr}");
    assert!(
        stdout.lines().any(|l| l == "validation messages: 0"),
        "{stdout}"
    );
    assert!(
        stderr.contains("playing the shipped per-sample shell maps"),
        "{stderr}"
    );
    assert!(
        stderr.contains("blends 11 per-sample shell maps"),
        "{stderr}"
    );
    assert!(!stderr.contains("solved"), "{stderr}");
    assert!(!Path::new(out).join("glass/room_shells.ptxc").exists());
}

/// `engine eval` on the compiled `out`: the hybrid row plays the three
/// per-sample maps (its samples and container bytes stated), the
/// traced-shell row the one traced map (none stated, other frames).
fn eval_states_the_shells(scene: &str, out: &Path, dir: &Path) {
    let eval = eval_hybrid_rows(scene, out, &dir.join("eval"), "hybrid,hybrid traced-shell");
    let row = |label: &str| eval_row(&eval, label);
    let (blended, traced) = (row("hybrid"), row("hybrid traced-shell"));
    assert_eq!(blended["samples"], 3, "{blended}");
    assert!(
        blended["map_bytes"].as_u64().is_some_and(|b| b > 0),
        "{blended}"
    );
    assert!(
        traced["samples"].is_null() && traced["map_bytes"].is_null(),
        "{traced}"
    );
    let on = |r: &serde_json::Value| r["psnr_on_db"].as_f64().expect("psnr_on_db");
    assert!(on(blended).is_finite() && on(traced).is_finite());
    assert_ne!(on(blended), on(traced), "the rows played the same maps");
}

#[test]
fn hybrid_without_glass_fails_cleanly() {
    let dir = tempfile::tempdir().expect("tempdir");
    let o = run("teapot", &dir.path().join("out"), &["--mode", "hybrid"]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && !stderr.contains("panicked"),
        "{stderr}"
    );
    let line = stderr
        .lines()
        .find(|l| l.starts_with("error:"))
        .unwrap_or_default();
    assert!(line.contains("[objects.glass]"), "{stderr}");
}

#[test]
fn a_near_object_plays_as_a_layer_traced_once() {
    let dir = tempfile::tempdir().expect("tempdir");
    let traced = [("shell_every = 10", "shell_every = 0")];
    let scene = small_scene(dir.path(), "glass_near", &traced);
    let out = dir.path().join("out");
    let stderr = run_clean(&scene, &out, &[]);
    for i in 1..=2 {
        assert!(
            stderr.contains(&format!("traced shell layer {i} of 2")),
            "{stderr}"
        );
    }
    assert!(
        stderr.contains("hybrid glass reads 2 shell layers, nearest first: quad"),
        "{stderr}"
    );
    assert!(!stderr.contains("per-sample"), "{stderr}");
    assert!(stderr.contains("placed in"), "{stderr}");
    assert!(out.join("glass/shells.json").is_file());

    // Cached: nothing placed or traced again. A damaged layer is traced again (that
    // one only); the one room shell plays without the layers.
    let stderr = run_clean(&scene, &out, &[]);
    assert!(!stderr.contains("traced shell layer"), "{stderr}");
    assert!(!stderr.contains("traced the room"), "{stderr}");
    assert!(!stderr.contains("placed in"), "{stderr}");
    std::fs::write(out.join("glass/layer_1.bin"), b"not a map").expect("damage");
    let stderr = run_clean(&scene, &out, &[]);
    assert!(stderr.contains("traced shell layer 2 of 2"), "{stderr}");
    assert!(!stderr.contains("traced shell layer 1 of 2"), "{stderr}");
    let one = run(&scene, &out, &["--traced-shell"]);
    let stderr = String::from_utf8_lossy(&one.stderr);
    assert!(one.status.success(), "stderr:\n{stderr}");
    assert!(!stderr.contains("shell layers"), "{stderr}");
    eval_states_the_layers(&scene, &out, dir.path());
}

/// A near object with per-sample maps asked for (lines 0 and 99, one view
/// each): `engine compile` solves both layers of both lines and packs them,
/// refusing to ship them; playing solves nothing and blends them, a
/// damaged map is solved again alone, `--traced-layers` plays the traced
/// layers, and eval's rows for the two score differently.
#[test]
fn near_layers_get_per_sample_maps_solved_once_and_blended() {
    let dir = tempfile::tempdir().expect("tempdir");
    let edits = [
        ("shell_every = 10", "shell_every = 99"),
        ("views = 3", "views = 1"),
    ];
    let scene = small_scene(dir.path(), "glass_near", &edits);
    let out = dir.path().join("out");
    let compile = |extra: &[&str]| compile(&scene, &out, extra);
    let o = compile(&["--ship", dir.path().join("ship").to_str().expect("utf-8")]);
    let log = common::output_text(&o);
    assert!(!o.status.success() && log.contains("not shipped"), "{log}");
    assert!(!dir.path().join("ship").exists(), "nothing shipped");
    let o = compile(&[]);
    let log = common::output_text(&o);
    assert!(o.status.success(), "{log}");
    assert!(
        log.contains("solved per-sample shell layer maps: 4 of 4 (2 orbit lines)"),
        "{log}"
    );
    assert!(log.contains("layer_shells.ptxc"), "{log}");
    let stderr = run_clean(&scene, &out, &[]);
    let blends = "blends 2 per-sample maps of each of its 2 shell layers";
    assert!(stderr.contains(blends), "{stderr}");
    assert!(!stderr.contains("solved"), "{stderr}");
    // Without its container, a damaged map is solved again, alone.
    std::fs::remove_file(out.join("glass/layer_shells.ptxc")).expect("container");
    std::fs::write(out.join("glass/layer_1_line0099.bin"), b"not a map").expect("damage");
    let stderr = run_clean(&scene, &out, &[]);
    let again = "solved per-sample shell layer maps: 1 of 4 (1 orbit lines)";
    assert!(
        stderr.contains(again) && stderr.contains(blends),
        "{stderr}"
    );
    let stderr = run_clean(&scene, &out, &["--traced-layers"]);
    assert!(
        !stderr.contains("per-sample") && stderr.contains("reads 2 shell layers"),
        "{stderr}"
    );
    let rows = "hybrid,hybrid traced-layers";
    let eval = eval_hybrid_rows(&scene, &out, &dir.path().join("eval"), rows);
    let (blended, traced) = (
        eval_row(&eval, "hybrid"),
        eval_row(&eval, "hybrid traced-layers"),
    );
    let between = |r: &serde_json::Value| r["psnr_between_db"].as_f64().expect("psnr");
    assert_ne!(between(blended), between(traced));
    assert_eq!(blended["samples"], 2, "{blended}");
    assert!(
        blended["map_bytes"].as_u64().is_some_and(|b| b > 0),
        "{blended}"
    );
    assert!(traced["samples"].is_null(), "{traced}");
}

/// `engine eval` on the compiled `out`: the hybrid row reads two layers,
/// the traced-shell row one, and they score differently.
fn eval_states_the_layers(scene: &str, out: &Path, dir: &Path) {
    let rows = "hybrid,hybrid traced-shell";
    let eval = eval_hybrid_rows(scene, out, &dir.join("eval_layers"), rows);
    let row = |label: &str| eval_row(&eval, label);
    let (layered, one) = (row("hybrid"), row("hybrid traced-shell"));
    assert_eq!(layered["shell_layers"], 2, "{layered}");
    assert_eq!(one["shell_layers"], 1, "{one}");
    let between = |r: &serde_json::Value| r["psnr_between_db"].as_f64().expect("psnr");
    assert_ne!(
        between(layered),
        between(one),
        "the rows played the same maps"
    );
}
