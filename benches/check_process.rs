//! Benchmark: `skillc check stdlib-skills/*.skill` as a whole process, as a user runs it
//! while typing (target: under 20 ms). Run with `cargo bench --bench check_process`.

use criterion::{criterion_group, criterion_main, Criterion};
use std::process::Command;

fn check_stdlib_process(c: &mut Criterion) {
    let root = env!("CARGO_MANIFEST_DIR");
    let files = ["touch", "press", "slide", "contour"].map(|name| format!("{root}/stdlib-skills/{name}.skill"));
    c.bench_function("skillc check stdlib-skills/*.skill", |b| {
        b.iter(|| {
            let status = Command::new(env!("CARGO_BIN_EXE_skillc"))
                .arg("check")
                .args(&files)
                .stderr(std::process::Stdio::null())
                .status()
                .expect("skillc runs");
            assert!(status.success());
        })
    });
}

criterion_group!(benches, check_stdlib_process);
criterion_main!(benches);
