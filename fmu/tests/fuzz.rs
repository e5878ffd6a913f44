//! Fuzzing on the stable toolchain: the map loader, the vision model loader, saved FMU
//! states and FMI call sequences, fed with mutated and random bytes. Each target holds an
//! invariant besides "no panic": whatever loads is valid, and every output the FMU gives is
//! finite. The tests run a bounded number of cases (seeds 0..n, and every single-byte
//! mutation class of a map file); `FUZZ_SECONDS=600 cargo test --release -p ftfusion
//! --test fuzz -- --nocapture --test-threads 1` runs each target for that long on fresh
//! seeds instead. A failure names the target and its seed: the case replays from it.

use std::ffi::CString;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use fmi_sys::fmi2::*;
use ftfusion::fmi2::*;
use ftmap::map::format;
use ftmap::vision::VisionModel;
use model_description::{Causality, VARIABLES, VarType};
use rand_xoshiro::Xoshiro256PlusPlus;
use rand_xoshiro::rand_core::{Rng, SeedableRng};

/// Runs `case` on seeds 0..`bounded`, or with `FUZZ_SECONDS` set on fresh seeds for that
/// long; fails naming the seed of the first case that panics or breaks its invariant.
fn fuzz(target: &str, bounded: u64, case: impl Fn(u64) -> Result<(), String>) {
    let budget = std::env::var("FUZZ_SECONDS")
        .ok()
        .and_then(|s| s.parse::<u64>().ok())
        .map(Duration::from_secs);
    let start = Instant::now();
    let first = match budget {
        Some(_) => start.elapsed().as_nanos() as u64 ^ u64::from(std::process::id()) << 32,
        None => 0,
    };
    let mut runs = 0u64;
    loop {
        let seed = first.wrapping_add(runs);
        let outcome = catch_unwind(AssertUnwindSafe(|| case(seed)));
        if !matches!(outcome, Ok(Ok(()))) {
            // The FMU's panic hook (installed by fmi2Instantiate: this process shares the
            // FMU's runtime) keeps panic messages quiet; the default one says this failure.
            drop(std::panic::take_hook());
        }
        match outcome {
            Ok(Ok(())) => {}
            Ok(Err(broken)) => panic!("{target}, seed {seed}: {broken}"),
            Err(p) => panic!("{target}, seed {seed}: panicked: {p:?}"),
        }
        runs += 1;
        let done = match budget {
            Some(b) => start.elapsed() >= b,
            None => runs >= bounded,
        };
        if done {
            break;
        }
    }
    println!(
        "{target}: {runs} cases in {:.1} s",
        start.elapsed().as_secs_f64()
    );
}

/// A scratch folder of this test process.
fn scratch() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("ftfusion-fuzz-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("scratch folder");
    dir
}

/// The bytes of a small valid map file (the analytic peg field, 9 x 9 cells).
fn map_bytes() -> Vec<u8> {
    format::to_bytes(&ftfusion_testkit::peg_map(1e-3, 2.5e-4, None).expect("map"))
}

/// `bytes` with 1 to 4 random mutations: a byte set, a bit flipped, a byte inserted or
/// removed, a range repeated, or the end cut off; positions favour the first `head` bytes.
fn mutate(bytes: &[u8], head: usize, rng: &mut Xoshiro256PlusPlus) -> Vec<u8> {
    let mut b = bytes.to_vec();
    for _ in 0..1 + rng.next_u32() % 4 {
        if b.is_empty() {
            break;
        }
        let span = if rng.next_u32().is_multiple_of(2) {
            head.min(b.len())
        } else {
            b.len()
        };
        let at = rng.next_u32() as usize % span.max(1);
        let byte = rng.next_u32() as u8;
        match rng.next_u32() % 7 {
            0 => b[at] = byte,
            1 => b[at] ^= 1 << (byte % 8),
            2 => b.insert(at, byte),
            3 => {
                b.remove(at);
            }
            4 => {
                let len = (rng.next_u32() as usize % 16).min(b.len() - at);
                let piece = b[at..at + len].to_vec();
                b.splice(at..at, piece);
            }
            5 => b.truncate(at),
            _ => b[at] = b"0123456789-.e,\"{}[]"[byte as usize % 19],
        }
    }
    b
}

/// Replaces a map file's last four bytes by the CRC of the rest (a mutation then reaches
/// the checks behind the checksum).
fn recrc(b: &mut [u8]) {
    if b.len() >= 4 {
        let n = b.len() - 4;
        let crc = crc32fast::hash(&b[..n]);
        b[n..].copy_from_slice(&crc.to_le_bytes());
    }
}

/// The invariant of the map loader on `bytes`: refused, or a map whose header passes the
/// checks, whose data fills the grid, and which the filter can use with finite outputs.
fn decode_holds(bytes: &[u8]) -> Result<(), String> {
    let Ok((map, shard)) = format::decode(bytes, Path::new("fuzz.ftmap")) else {
        return Ok(());
    };
    if map.data().len() != map.grid().cells() * ftmap::NCH {
        return Err("data does not fill the grid".into());
    }
    if shard.is_some() {
        return Ok(());
    }
    if let Some(v) = map.data().iter().find(|v| !v.is_finite()) {
        return Err(format!("a whole map loaded with a cell value {v}"));
    }
    let cfg = ftfusion::Config {
        particles: 50,
        iterations: 2,
        ..ftfusion::Config::default()
    };
    let mut f = ftfusion::Filter::new(&map, Path::new("fuzz.ftmap"), cfg)
        .map_err(|e| format!("a loaded map that the filter refuses: {e}"))?;
    let m = ftfusion::Measurement {
        wrench: [1.0, -2.0, 50.0, 0.1, -0.2, 0.0],
        tcp: [1e-4, -1e-4, 0.01, 0.0, 0.0, 0.0],
        ..ftfusion::Measurement::default()
    };
    f.measure(&m).map_err(|e| e.to_string())?;
    let e = f.estimate();
    if e.pose.iter().chain(&e.std).any(|v| !v.is_finite()) || !e.confidence.is_finite() {
        return Err(format!("a non-finite estimate on a loaded map: {e:?}"));
    }
    Ok(())
}

#[test]
fn every_single_byte_mutation_class_of_a_map_file_is_refused_or_valid() {
    let base = map_bytes();
    let mut cases = 0;
    for at in 0..base.len() {
        let classes = [
            0x00,
            0xff,
            base[at].wrapping_add(1),
            base[at].wrapping_sub(1),
        ]
        .into_iter()
        .chain((0..8).map(|k| base[at] ^ (1 << k)));
        for byte in classes {
            let mut b = base.clone();
            b[at] = byte;
            recrc(&mut b);
            decode_holds(&b)
                .map_err(|e| format!("byte {at} = {byte:#04x}: {e}"))
                .unwrap();
            cases += 1;
        }
    }
    assert!(cases > 10 * base.len());
}

#[test]
fn fuzz_the_map_loader() {
    let base = map_bytes();
    let head = 16 + u32::from_le_bytes(base[12..16].try_into().expect("4 bytes")) as usize;
    fuzz("map loader", 5000, |seed| {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        let mut b = mutate(&base, head, &mut rng);
        if rng.next_u32() % 8 != 0 {
            recrc(&mut b);
        }
        decode_holds(&b)
    });
}

#[test]
fn fuzz_the_vision_model_loader() {
    let dir = scratch();
    let valid = dir.join("valid.vision.json");
    ftfusion_testkit::bearing_vision()
        .save(&valid)
        .expect("write");
    let base = std::fs::read(&valid).expect("read");
    let (file, again) = (dir.join("fuzz.vision.json"), dir.join("again.vision.json"));
    fuzz("vision model loader", 3000, |seed| {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        std::fs::write(&file, mutate(&base, base.len(), &mut rng)).map_err(|e| e.to_string())?;
        // Whatever loads is a model the loader takes back after writing it (equal to a
        // float's last bit: serde_json's parser rounds long decimals within an ulp).
        if let Ok(m) = VisionModel::load(&file) {
            m.save(&again).map_err(|e| e.to_string())?;
            VisionModel::load(&again)
                .map_err(|e| format!("a loaded model is refused once written: {e}"))?;
        }
        Ok(())
    });
}

/// A logger-less instance of the FMU (through its C interface) with the resources folder
/// holding the small map as `peg.ftmap`.
struct Fmu {
    c: fmi2Component,
    _functions: Box<fmi2CallbackFunctions>,
}

impl Fmu {
    fn new(resources: &Path) -> Self {
        let functions = Box::new(fmi2CallbackFunctions {
            logger: None,
            allocateMemory: None,
            freeMemory: None,
            stepFinished: None,
            componentEnvironment: std::ptr::null_mut(),
        });
        let name = CString::new("fuzz").expect("name");
        let guid = CString::new(model_description::guid()).expect("guid");
        let url = CString::new(format!("file://{}", resources.display())).expect("url");
        // SAFETY: valid C strings and callbacks, as an importer passes them.
        let c = unsafe {
            fmi2Instantiate(
                name.as_ptr(),
                fmi2Type_fmi2CoSimulation,
                guid.as_ptr(),
                url.as_ptr(),
                &*functions,
                0,
                0,
            )
        };
        assert!(!c.is_null(), "fmi2Instantiate");
        Self {
            c,
            _functions: functions,
        }
    }

    fn set_real(&self, vr: u32, v: f64) -> fmi2Status {
        // SAFETY: one value reference and one value.
        unsafe { fmi2SetReal(self.c, &vr, 1, &v) }
    }

    fn set_int(&self, vr: u32, v: i32) -> fmi2Status {
        // SAFETY: as above.
        unsafe { fmi2SetInteger(self.c, &vr, 1, &v) }
    }

    fn set_bool(&self, vr: u32, v: bool) -> fmi2Status {
        let b = fmi2Boolean::from(v);
        // SAFETY: as above.
        unsafe { fmi2SetBoolean(self.c, &vr, 1, &b) }
    }

    fn set_string(&self, vr: u32, v: &str) -> fmi2Status {
        let s = CString::new(v).expect("no NUL");
        let p = s.as_ptr();
        // SAFETY: as above.
        unsafe { fmi2SetString(self.c, &vr, 1, &p) }
    }

    /// Every Real output, when the FMU gives them.
    fn outputs(&self) -> Option<Vec<(&'static str, f64)>> {
        let outs: Vec<_> = VARIABLES
            .iter()
            .filter(|v| v.causality == Causality::Output && v.ty == VarType::Real)
            .collect();
        let vrs: Vec<u32> = outs.iter().map(|v| v.vr).collect();
        let mut values = vec![0.0; vrs.len()];
        // SAFETY: matching lengths.
        let s = unsafe { fmi2GetReal(self.c, vrs.as_ptr(), vrs.len(), values.as_mut_ptr()) };
        (s == fmi2Status_fmi2OK).then(|| outs.iter().map(|v| v.name).zip(values).collect())
    }

    /// Errors naming the first output that breaks the filter's invariants: every output
    /// finite, the estimate inside Omega (the small map's ±1 mm), spreads >= 0 and the
    /// confidence a share of the weight.
    fn sound(&self) -> Result<(), String> {
        for (name, v) in self.outputs().unwrap_or_default() {
            let ok = match name {
                _ if !v.is_finite() => false,
                "object.x" | "object.y" => v.abs() <= 1e-3 * (1.0 + 1e-9),
                "confidence" => (0.0..=1.0 + 1e-9).contains(&v),
                n if n.ends_with("_std") => v >= 0.0,
                _ => true,
            };
            if !ok {
                return Err(format!("output {name} = {v}"));
            }
        }
        Ok(())
    }

    /// The state as serialized bytes.
    fn save(&self) -> Option<Vec<u8>> {
        let mut state: fmi2FMUstate = std::ptr::null_mut();
        // SAFETY: writable pointers; the state is freed below.
        unsafe {
            if fmi2GetFMUstate(self.c, &mut state) != fmi2Status_fmi2OK {
                return None;
            }
            let mut size = 0;
            fmi2SerializedFMUstateSize(self.c, state, &mut size);
            let mut bytes = vec![0u8; size];
            let s = fmi2SerializeFMUstate(self.c, state, bytes.as_mut_ptr() as *mut _, size);
            fmi2FreeFMUstate(self.c, &mut state);
            (s == fmi2Status_fmi2OK).then_some(bytes)
        }
    }

    /// Deserializes `bytes` and sets the state: the status.
    fn restore(&self, bytes: &[u8]) -> fmi2Status {
        let mut state: fmi2FMUstate = std::ptr::null_mut();
        // SAFETY: `bytes` holds its length; the state is freed below.
        unsafe {
            let s = fmi2DeSerializeFMUstate(
                self.c,
                bytes.as_ptr() as *const _,
                bytes.len(),
                &mut state,
            );
            if s != fmi2Status_fmi2OK {
                return s;
            }
            let s = fmi2SetFMUstate(self.c, state);
            fmi2FreeFMUstate(self.c, &mut state);
            s
        }
    }

    fn step(&self, t: f64, h: f64) -> fmi2Status {
        // SAFETY: a live instance.
        unsafe { fmi2DoStep(self.c, t, h, 0) }
    }
}

impl Drop for Fmu {
    fn drop(&mut self) {
        // SAFETY: the instance from fmi2Instantiate, freed once.
        unsafe { fmi2FreeInstance(self.c) }
    }
}

fn vr(name: &str) -> u32 {
    model_description::by_name(name).expect("variable").vr
}

/// A resources folder with the small map as `peg.ftmap`, written once per process.
fn resources() -> PathBuf {
    static DIR: std::sync::OnceLock<PathBuf> = std::sync::OnceLock::new();
    DIR.get_or_init(|| {
        let dir = scratch().join("resources");
        std::fs::create_dir_all(&dir).expect("resources");
        std::fs::write(dir.join("peg.ftmap"), map_bytes()).expect("map");
        dir
    })
    .clone()
}

/// An initialized instance (100 particles) after two contacts.
fn stepped() -> Fmu {
    let f = Fmu::new(&resources());
    f.set_string(vr("map"), "peg.ftmap");
    f.set_int(vr("particles"), 100);
    // SAFETY: a live instance.
    unsafe {
        fmi2EnterInitializationMode(f.c);
        assert_eq!(fmi2ExitInitializationMode(f.c), fmi2Status_fmi2OK);
    }
    for (k, w) in [
        [0.5, -1.0, 50.0, 0.1, -0.05, 0.0],
        [0.0, 0.0, 50.0, -0.1, 0.08, 0.0],
    ]
    .iter()
    .enumerate()
    {
        for (name, v) in model_description::WRENCH.iter().zip(w) {
            f.set_real(vr(name), *v);
        }
        f.set_real(vr("tcp.z"), 0.01);
        f.set_bool(vr("contact"), true);
        f.step(k as f64, 0.1);
        f.set_bool(vr("contact"), false);
        f.step(k as f64 + 0.1, 0.1);
    }
    f
}

#[test]
fn fuzz_saved_states() {
    let base = stepped().save().expect("a state");
    fuzz("FMU state deserialization", 2000, |seed| {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        let bytes = mutate(&base, 64, &mut rng);
        for f in [stepped(), Fmu::new(&resources())] {
            if f.restore(&bytes) == fmi2Status_fmi2OK {
                f.sound()?;
                f.set_bool(vr("contact"), true);
                f.step(10.0, 0.1);
                f.sound()?;
            }
        }
        Ok(())
    });
}

#[test]
fn fuzz_fmi_call_sequences() {
    let inputs: Vec<u32> = VARIABLES
        .iter()
        .filter(|v| v.causality == Causality::Input && v.ty == VarType::Real)
        .map(|v| v.vr)
        .collect();
    let params: Vec<_> = VARIABLES
        .iter()
        .filter(|v| v.causality == Causality::Parameter && v.ty != VarType::String)
        .collect();
    let flags = [vr("contact"), vr("vision.valid"), vr("slide")];
    let hostile = [
        0.0,
        1e-3,
        -2e-3,
        0.01,
        50.0,
        1.0,
        1e-9,
        1e6,
        -1e6,
        2e19,
        1e308,
        f64::NAN,
        f64::INFINITY,
        -f64::INFINITY,
        f64::MIN_POSITIVE,
        0.5,
    ];
    let ints = [0, 1, 2, 10, 20, 100, 1000, -1, i32::MAX, i32::MIN];
    let maps = ["peg.ftmap", "", "nothere.ftmap", "/dev/zero", "/etc/passwd"];
    fuzz("FMI call sequences", 5000, |seed| {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        let f = Fmu::new(&resources());
        f.set_int(vr("particles"), 50);
        f.set_int(vr("iterations"), 2);
        f.set_string(vr("map"), "peg.ftmap");
        let mut saved: Option<Vec<u8>> = None;
        let mut t = 0.0;
        let pick = |rng: &mut Xoshiro256PlusPlus, n: usize| rng.next_u32() as usize % n;
        // Mostly plausible values, a hostile one in five.
        let real = |rng: &mut Xoshiro256PlusPlus| match rng.next_u32() % 5 {
            0 => hostile[pick(rng, hostile.len())],
            _ => (f64::from(rng.next_u32()) / f64::from(u32::MAX) - 0.5) * 0.01,
        };
        // Any value, or (`valid`) one within the parameter's range, its ends included.
        let param = |rng: &mut Xoshiro256PlusPlus, valid: bool| {
            let v = params[pick(rng, params.len())];
            let (lo, hi) = (v.min.unwrap_or(-10.0), v.max.unwrap_or(10.0));
            let x = match rng.next_u32() % 4 {
                _ if !valid => real(rng),
                0 => lo,
                1 => hi,
                _ => lo + (hi - lo) * f64::from(rng.next_u32() % 1000) / 1000.0,
            };
            match v.ty {
                VarType::Real => f.set_real(v.vr, x),
                _ if valid => f.set_int(v.vr, x.round() as i32),
                _ => f.set_int(v.vr, ints[pick(rng, ints.len())]),
            };
        };
        // Usually a run: a few parameters, initialization, then measurements; any call may
        // come in any state all the same.
        for _ in 0..rng.next_u32() % 3 {
            param(&mut rng, true);
        }
        // Small runs: particles and iterations drawn from the whole range would be slow.
        f.set_int(vr("particles"), 50);
        f.set_int(vr("iterations"), 2);
        if rng.next_u32() % 4 != 0 {
            // SAFETY: a live instance.
            unsafe {
                fmi2EnterInitializationMode(f.c);
                fmi2ExitInitializationMode(f.c);
            }
        }
        for _ in 0..40 {
            // SAFETY (every call): a live instance and valid pointers.
            match rng.next_u32() % 40 {
                0 | 1 => param(&mut rng, false),
                2 => {
                    f.set_string(vr("map"), maps[pick(&mut rng, maps.len())]);
                }
                3 => unsafe {
                    fmi2EnterInitializationMode(f.c);
                },
                4 => unsafe {
                    fmi2ExitInitializationMode(f.c);
                },
                5..=16 => {
                    let v = real(&mut rng);
                    f.set_real(inputs[pick(&mut rng, inputs.len())], v);
                }
                17..=22 => {
                    f.set_bool(
                        flags[pick(&mut rng, flags.len())],
                        rng.next_u32().is_multiple_of(2),
                    );
                }
                23..=32 => {
                    let h = [0.1, 0.1, 0.1, 0.0, -1.0, f64::NAN][pick(&mut rng, 6)];
                    f.step(t, h);
                    t += 0.1;
                }
                33..=35 => saved = f.save().or(saved),
                36..=38 => {
                    if let Some(s) = &saved {
                        f.restore(s);
                    }
                }
                _ if rng.next_u32().is_multiple_of(2) => unsafe {
                    fmi2Reset(f.c);
                },
                _ => unsafe {
                    fmi2Terminate(f.c);
                },
            }
            f.sound()?;
        }
        Ok(())
    });
}
