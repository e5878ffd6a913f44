//! The `ftmap` command line as a user runs it: generate, info, export-csv, plot, shards
//! and merge, and clear refusals of bad input.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn ftmap(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_ftmap"))
        .args(args)
        .output()
        .expect("ftmap runs")
}

fn ok(args: &[&str]) -> String {
    let out = ftmap(args);
    assert!(
        out.status.success(),
        "ftmap {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// A scratch folder with a small peg task (x, y in ±1 mm at 0.5 mm) using the real meshes.
fn scratch(name: &str) -> (PathBuf, PathBuf) {
    let dir = std::env::temp_dir().join(format!("ftmap-cli-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("scratch task");
    let models = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models_mjcf/peg_in_hole");
    let text = std::fs::read_to_string(models.join("task.toml"))
        .expect("scratch task")
        .replace("size_trans = 0.005", "size_trans = 0.001")
        .replace("delta_trans = 0.0001", "delta_trans = 0.0005")
        .replace("\"peg.stl\"", &format!("{:?}", models.join("peg.stl")))
        .replace("\"block.stl\"", &format!("{:?}", models.join("block.stl")));
    let task = dir.join("task.toml");
    std::fs::write(&task, text).expect("scratch task");
    (dir, task)
}

#[test]
fn generate_info_export_and_plot_agree_with_each_other() {
    let (dir, task) = scratch("main");
    let map = dir.join("peg.ftmap");
    let out = ok(&[
        "generate",
        "--task",
        task.to_str().unwrap(),
        "--out",
        map.to_str().unwrap(),
    ]);
    assert!(out.contains("configs/s"), "{out}");
    let info = ok(&["info", map.to_str().unwrap()]);
    assert!(
        info.contains("object.x") && info.contains("81 cells") && info.contains("Centroid"),
        "{info}"
    );
    // Omega's ±1 mm sampled out to ±2 mm at 0.5 mm: 9 x 9 cells.
    assert!(
        info.contains("-2.000 mm .. +2.000 mm step 0.500 mm (9 samples, Omega ±1.000 mm)"),
        "{info}"
    );
    // The fit's clearance, from the task's [geometry] (Ø 10.0 mm hole, Ø 9.9 mm peg).
    assert!(info.contains("clearance  0.0500 mm"), "{info}");

    let csv_path = dir.join("peg.csv");
    ok(&[
        "export-csv",
        map.to_str().unwrap(),
        "--out",
        csv_path.to_str().unwrap(),
    ]);
    let mut rd = csv::Reader::from_path(&csv_path).unwrap();
    let header: Vec<String> = rd.headers().unwrap().iter().map(str::to_owned).collect();
    assert_eq!(
        header,
        [
            "object.x", "object.y", "fx", "fy", "fz", "tx", "ty", "tz", "depth"
        ]
    );
    let loaded = ftmap::map::format::load(&map).unwrap();
    let mut rows = 0;
    for rec in rd.records() {
        let v: Vec<f64> = rec.unwrap().iter().map(|s| s.parse().unwrap()).collect();
        let cell = loaded.nearest(&v[..2]).unwrap();
        for (c, x) in cell.iter().zip(&v[2..]) {
            assert_eq!(*c, *x as f32, "csv row {v:?} vs map {cell:?}");
        }
        rows += 1;
    }
    assert_eq!(rows, 81);

    let png = dir.join("ty.png");
    ok(&[
        "plot",
        map.to_str().unwrap(),
        "--channel",
        "ty",
        "--out",
        png.to_str().unwrap(),
    ]);
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    let bad = ftmap(&[
        "plot",
        map.to_str().unwrap(),
        "--channel",
        "tq",
        "--out",
        png.to_str().unwrap(),
    ]);
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("unknown channel `tq`"));
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn shards_merge_into_the_whole_map() {
    let (dir, _) = scratch("shards");
    // Shards split the rotation cells: add rx to the small task.
    let text = std::fs::read_to_string(dir.join("task.toml"))
        .unwrap()
        .replace("object = [\"x\", \"y\"]", "object = [\"x\", \"y\", \"rx\"]")
        .replace("size_rot = 0.0", "size_rot = 0.017453292519943295");
    let task = dir.join("task4.toml");
    std::fs::write(&task, text).unwrap();
    let t = task.to_str().unwrap();
    let whole = dir.join("whole.ftmap");
    ok(&["generate", "--task", t, "--out", whole.to_str().unwrap()]);
    let parts: Vec<PathBuf> = (0..2).map(|i| dir.join(format!("part{i}.ftmap"))).collect();
    for (i, p) in parts.iter().enumerate() {
        ok(&[
            "generate",
            "--task",
            t,
            "--shard",
            &format!("{i}/2"),
            "--out",
            p.to_str().unwrap(),
        ]);
    }
    // A shard is not a map: the loader says so.
    let refused = ftmap(&[
        "export-csv",
        parts[0].to_str().unwrap(),
        "--out",
        dir.join("x.csv").to_str().unwrap(),
    ]);
    assert!(String::from_utf8_lossy(&refused.stderr).contains("shard 0 of 2"));
    let merged = dir.join("merged.ftmap");
    let mut args = vec!["merge"];
    args.extend(parts.iter().map(|p| p.to_str().unwrap()));
    args.extend(["--out", merged.to_str().unwrap()]);
    ok(&args);
    let (a, b) = (
        ftmap::map::format::load(&whole).unwrap(),
        ftmap::map::format::load(&merged).unwrap(),
    );
    assert_eq!(a.data(), b.data());
    let missing = ftmap(&[
        "merge",
        parts[0].to_str().unwrap(),
        "--out",
        merged.to_str().unwrap(),
    ]);
    assert!(String::from_utf8_lossy(&missing.stderr).contains("shard 1/2 is missing"));
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn bad_input_gets_an_error_that_names_the_problem() {
    let (dir, task) = scratch("bad");
    let cases: Vec<(Vec<String>, &str)> = vec![
        (
            vec!["info".into(), dir.join("none.ftmap").display().to_string()],
            "No such file",
        ),
        (
            vec![
                "generate".into(),
                "--task".into(),
                "no_such_task".into(),
                "--out".into(),
                "x".into(),
            ],
            "known tasks",
        ),
    ];
    for (args, expect) in cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let out = ftmap(&args);
        assert!(!out.status.success());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(expect), "{args:?}: {err}");
    }
    // A missing mesh is named.
    let text = std::fs::read_to_string(&task)
        .unwrap()
        .replace("peg.stl", "gone.stl");
    std::fs::write(&task, text).unwrap();
    let out = ftmap(&[
        "generate",
        "--task",
        task.to_str().unwrap(),
        "--out",
        dir.join("m.ftmap").to_str().unwrap(),
    ]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("gone.stl"));
    // A corrupted map is refused as corrupted.
    let (dir2, task2) = scratch("bad2");
    let map = dir2.join("m.ftmap");
    ok(&[
        "generate",
        "--task",
        task2.to_str().unwrap(),
        "--out",
        map.to_str().unwrap(),
    ]);
    let mut bytes = std::fs::read(&map).unwrap();
    let n = bytes.len();
    bytes[n - 20] ^= 1;
    std::fs::write(&map, &bytes).unwrap();
    let out = ftmap(&["info", map.to_str().unwrap()]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("corrupted: checksum"));
    std::fs::write(&map, &bytes[..n / 2]).unwrap();
    let out = ftmap(&["info", map.to_str().unwrap()]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("truncated"));
    // A header whose cell count wraps the size (one axis of 2^60 cells, 20 bytes of data,
    // the checksum right): refused by `info` and `export-csv` alike, naming the problem.
    let json = format!(
        "{{\"kind\":\"ftmap\",\"grid\":{{\"axes\":[{{\"dof\":\"object.x\",\"min\":0.0,\"step\":1e-16,\"count\":{}}}]}},\"channels\":[\"fx\",\"fy\",\"fz\",\"tx\",\"ty\",\"tz\",\"depth\"],\"units\":[\"N\",\"N\",\"N\",\"N.m\",\"N.m\",\"N.m\",\"m\"],\"meta\":{{\"task\":\"t\",\"model\":\"centroid\",\"approach\":[0.0,0.0,-1.0],\"force\":50.0,\"friction\":0.3,\"sensor_origin\":[0.0,0.0,0.06],\"pixel\":0.0001,\"sources\":[],\"generator\":\"t\"}}}}",
        1u64 << 60
    );
    let mut wrap = b"FTMAP\0\r\n".to_vec();
    wrap.extend_from_slice(&1u32.to_le_bytes());
    wrap.extend_from_slice(&(json.len() as u32).to_le_bytes());
    wrap.extend_from_slice(json.as_bytes());
    wrap.extend_from_slice(&[0u8; 20]);
    let crc = crc32fast::hash(&wrap);
    wrap.extend_from_slice(&crc.to_le_bytes());
    std::fs::write(&map, &wrap).unwrap();
    for cmd in [&["info"][..], &["export-csv", "--out", "/dev/null"]] {
        let mut args = cmd.to_vec();
        args.insert(1, map.to_str().unwrap());
        let out = ftmap(&args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?}");
        assert!(
            err.contains("more than a map file may hold") && !err.contains("panicked"),
            "{args:?}: {err}"
        );
    }
    std::fs::remove_dir_all(dir).ok();
    std::fs::remove_dir_all(dir2).ok();
}

#[test]
fn vision_writes_the_tasks_model_and_refuses_a_task_without_a_camera() {
    let dir = std::env::temp_dir().join(format!("ftmap-cli-vision-{}", std::process::id()));
    let out = dir.join("bearing.vision.json");
    let text = ok(&[
        "vision",
        "--task",
        "bearing_housing",
        "--out",
        out.to_str().expect("utf-8 path"),
    ]);
    assert!(text.contains("640x480"), "{text}");
    let m = ftmap::vision::VisionModel::load(&out).expect("a valid vision model");
    // task.toml: 200 mm in front, aimed at z = 14 mm on x = 0, 8 degrees down.
    let want = [-0.2, 0.0, 0.014 + 0.2 * 8f64.to_radians().tan()];
    assert!(
        m.camera
            .pos
            .iter()
            .zip(want)
            .all(|(a, b)| (a - b).abs() < 1e-12),
        "{:?}",
        m.camera.pos
    );
    assert_eq!(
        m.passive.outline,
        ftmap::vision::Outline::Circle { radius: 0.01095 }
    );
    let bad = ftmap(&[
        "vision",
        "--task",
        "peg_in_hole",
        "--out",
        out.to_str().expect("utf-8 path"),
    ]);
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(
        !bad.status.success() && err.contains("peg_in_hole") && err.contains("[camera]"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn blend_corrects_a_computed_map_by_a_measured_one() {
    let (dir, task) = scratch("blend");
    let computed = dir.join("peg.ftmap");
    ok(&[
        "generate",
        "--task",
        task.to_str().unwrap(),
        "--out",
        computed.to_str().unwrap(),
    ]);
    // A "measured" map on the same cells whose tx is 0.01 N m larger everywhere.
    let c = ftmap::map::format::load(&computed).unwrap();
    let mut data = c.data().to_vec();
    for cell in data.chunks_exact_mut(ftmap::NCH) {
        cell[3] += 0.01;
    }
    let meta = ftmap::MapMeta {
        model: ftmap::WrenchModel::Measured,
        ..c.meta().clone()
    };
    let m = ftmap::FtMap::from_data(c.grid().clone(), meta, data).unwrap();
    let measured = dir.join("measured.ftmap");
    ftmap::map::format::save(&m, &measured).unwrap();
    let blended = dir.join("blended.ftmap");
    let out = ok(&[
        "blend",
        computed.to_str().unwrap(),
        measured.to_str().unwrap(),
        "--out",
        blended.to_str().unwrap(),
    ]);
    assert!(out.contains("81 measured cells"), "{out}");
    let b = ftmap::map::format::load(&blended).unwrap();
    assert_eq!(b.meta().model, ftmap::WrenchModel::Blended);
    for (x, y) in b.data().iter().zip(m.data()) {
        assert!((x - y).abs() < 1e-6, "{x} vs {y}");
    }
    assert!(ok(&["info", blended.to_str().unwrap()]).contains("Blended"));
    // Two computed maps are refused, naming why.
    let refused = ftmap(&[
        "blend",
        computed.to_str().unwrap(),
        computed.to_str().unwrap(),
        "--out",
        dir.join("x.ftmap").to_str().unwrap(),
    ]);
    assert!(!refused.status.success());
    assert!(String::from_utf8_lossy(&refused.stderr).contains("measured"));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_grid_too_coarse_for_the_fit_is_warned_of_and_no_other() {
    let (dir, task) = scratch("coarse");
    let base = std::fs::read_to_string(&task).unwrap();
    // The peg's fit: 0.05 mm radial clearance, a diametral gap of 0.1 mm.
    let variant = |name: &str, edits: &[(&str, &str)]| {
        let text = edits
            .iter()
            .fold(base.clone(), |t, (from, to)| t.replace(from, to));
        assert!(edits.is_empty() || text != base, "{name}: the edits apply");
        let path = dir.join(format!("{name}.toml"));
        std::fs::write(&path, text).unwrap();
        let map = dir.join(format!("{name}.ftmap"));
        let out = ftmap(&[
            "generate",
            "--task",
            path.to_str().unwrap(),
            "--out",
            map.to_str().unwrap(),
        ]);
        assert!(out.status.success(), "{name}");
        let info = ok(&["info", map.to_str().unwrap()]);
        (String::from_utf8_lossy(&out.stderr).into_owned(), info)
    };
    let rx = [
        ("object = [\"x\", \"y\"]", "object = [\"x\", \"y\", \"rx\"]"),
        ("size_rot = 0.0", "size_rot = 0.017453292519943295"),
    ];
    // x, y at 0.5 mm: the negative contact states the fit exactly, no warning.
    let (err, info) = variant("planar", &[]);
    assert!(
        !err.contains("warning") && !info.contains("warning"),
        "{err}{info}"
    );
    // With a rotation, a 0.5 mm step hides where the part goes in: warned by both commands.
    let (err, info) = variant("rotation", &rx);
    for text in [&err, &info] {
        assert!(
            text.contains("object.x's step 0.5000 mm") && text.contains("gap 0.1000 mm"),
            "{text}"
        );
    }
    // The same at a step equal to the gap: no warning.
    let fine = [
        rx[0],
        rx[1],
        ("delta_trans = 0.0005", "delta_trans = 0.0001"),
    ];
    let (err, info) = variant("rotation_fine", &fine);
    assert!(
        !err.contains("warning") && !info.contains("warning"),
        "{err}{info}"
    );
    // A pixel wider than the gap: warned even on x, y alone.
    let (err, info) = variant("pixel", &[("pixel = 0.0001", "pixel = 0.00025")]);
    for text in [&err, &info] {
        assert!(text.contains("the pixel 0.2500 mm"), "{text}");
    }
}

#[test]
fn a_centre_map_is_computed_where_the_step_is_too_coarse_beside_a_rotation() {
    let (dir, task) = scratch("centre");
    let rotation = std::fs::read_to_string(&task)
        .unwrap()
        .replace("object = [\"x\", \"y\"]", "object = [\"x\", \"y\", \"rx\"]")
        .replace("size_rot = 0.0", "size_rot = 0.017453292519943295");
    let turned = dir.join("turned.toml");
    std::fs::write(&turned, rotation).unwrap();
    let (map, centre) = (dir.join("m.ftmap"), dir.join("c.ftmap"));
    let path = |p: &Path| p.to_str().unwrap().to_owned();
    let run = |t: &Path| {
        ok(&[
            "generate",
            "--task",
            &path(t),
            "--out",
            &path(&map),
            "--centre",
            &path(&centre),
        ])
    };
    // x, y alone: the negative contact states the fit, no centre map.
    assert!(run(&task).contains("no centre map"));
    assert!(!centre.exists());
    // Beside rx, the 0.5 mm step in tenths within the 0.05 mm clearance, over ±1 mm; the
    // pixel the step, the rotation as the map's.
    run(&turned);
    let info = ok(&["info", &path(&centre)]);
    for text in [
        "object.x   -1.000 mm .. +1.000 mm step 0.050 mm (41 samples)",
        "object.rx  -1.000 deg .. +1.000 deg step 0.500 deg (5 samples)",
        "pixel 0.05 mm",
    ] {
        assert!(info.contains(text), "{text}: {info}");
    }
    let (m, _) = ftmap::map::format::load_any(&map).unwrap();
    let (c, _) = ftmap::map::format::load_any(&centre).unwrap();
    m.check_centre(&c).expect("a centre map of the map");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_reader_that_goes_away_ends_the_output_without_a_panic() {
    // `ftmap info F | head -1`: the reader closes the pipe before ftmap writes. Unix tools
    // end by SIGPIPE there; Rust's runtime ignores it, and printing then panicked.
    use std::os::unix::process::ExitStatusExt;
    let (dir, task) = scratch("pipe");
    let map = dir.join("peg.ftmap");
    ok(&[
        "generate",
        "--task",
        task.to_str().unwrap(),
        "--out",
        map.to_str().unwrap(),
    ]);
    let (reader, writer) = std::io::pipe().expect("a pipe");
    drop(reader);
    let out = Command::new(env!("CARGO_BIN_EXE_ftmap"))
        .args(["info", map.to_str().unwrap()])
        .stdout(writer)
        .output()
        .expect("ftmap runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(out.status.signal(), Some(libc::SIGPIPE), "{:?}", out.status);
    std::fs::remove_dir_all(&dir).ok();
}

/// `FTMAP_REQUIRE_GPU=1` (as the docs write it) is read as asking for a GPU: where the only
/// Vulkan adapter is a CPU one (lavapipe, as in CI) the GPU backend is refused by name; on
/// a real GPU the map is computed there. `0` asks for nothing, and other words are refused.
#[test]
fn the_require_gpu_variable_reads_as_the_docs_write_it() {
    let (dir, task) = scratch("require");
    let run = |value: &str| {
        Command::new(env!("CARGO_BIN_EXE_ftmap"))
            .args(["generate", "--backend", "gpu", "--task"])
            .arg(&task)
            .arg("--out")
            .arg(dir.join("m.ftmap"))
            .env("FTMAP_REQUIRE_GPU", value)
            .output()
            .expect("ftmap runs")
    };
    let out = run("1");
    let err = String::from_utf8_lossy(&out.stderr);
    if out.status.success() {
        let adapter = err.lines().find(|l| l.starts_with("GPU adapter:"));
        assert!(
            adapter.is_some_and(|l| !l.contains("(Cpu)")),
            "a GPU was required, yet: {err}"
        );
    } else {
        assert!(
            err.contains("a GPU was required") || err.contains("no Vulkan adapter"),
            "{err}"
        );
    }
    let out = run("no");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !err.contains("a GPU was required") && !err.contains("invalid value"),
        "{err}"
    );
    let out = run("perhaps");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("invalid value 'perhaps' for '--require-gpu'"),
        "{err}"
    );
    std::fs::remove_dir_all(dir).ok();
}
