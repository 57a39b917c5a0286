//! Benchmark: parse + check + lower of each standard skill, in process (target: under 1 ms each).

use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;

const STDLIB: [(&str, &str); 4] = [
    ("touch", include_str!("../stdlib-skills/touch.skill")),
    ("press", include_str!("../stdlib-skills/press.skill")),
    ("slide", include_str!("../stdlib-skills/slide.skill")),
    ("contour", include_str!("../stdlib-skills/contour.skill")),
];

fn compile_stdlib(c: &mut Criterion) {
    let mut group = c.benchmark_group("compile");
    for (name, text) in STDLIB {
        group.bench_function(name, |b| {
            b.iter(|| {
                let compilation = skill_compiler::compile_str(name, black_box(text));
                assert!(compilation.program.is_some());
                compilation
            })
        });
    }
    group.finish();
}

criterion_group!(benches, compile_stdlib);
criterion_main!(benches);
