//! `rayreel bench --only kernels` through the binary: every kernel in f64, the packet kernels in
//! f32 too, the same frame from every width in each precision, and the widest kernel's f32 over
//! f64 line with its target. Lines are parsed, never judged on speed (`--quick`, one run).

mod common;

use common::{run_in, scratch, stderr};
use rayreel::tracer::Kernel;

/// The numbers in `frames/s (…x)` figures and the ratio line parse; the figures follow the
/// header's kernel names in order.
#[test]
fn kernels_bench_lists_f32_variants_and_their_ratio() {
    let tmp = scratch("bench");
    let out = run_in(
        &tmp,
        &["bench", "--only", "kernels", "--quick", "--runs", "1"],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let text = String::from_utf8_lossy(&out.stdout);
    let kernels: Vec<Kernel> = Kernel::ALL.into_iter().filter(|k| k.supported()).collect();
    let mut names: Vec<String> = kernels.iter().map(|k| k.name().to_string()).collect();
    let packets: Vec<&Kernel> = kernels.iter().filter(|&&k| k != Kernel::Scalar).collect();
    names.extend(packets.iter().map(|k| format!("{} f32", k.name())));
    let header = format!("kernels {} interleaved", names.join(", "));
    assert!(text.contains(&header), "{header} in\n{text}");
    let cases: Vec<&str> = text
        .lines()
        .filter(|l| l.starts_with("  ") && !l.starts_with("    "))
        .collect();
    assert_eq!(cases.len(), 3, "{text}");
    let same = match packets.is_empty() {
        true => "same frame from every kernel: f64 yes",
        false => "same frame from every kernel: f64 yes, f32 yes",
    };
    for line in &cases {
        assert!(line.ends_with(same), "{line}");
        let figures = line.split_once(": ").unwrap().1.split("; ").next().unwrap();
        let figures: Vec<&str> = figures.split(", ").collect();
        assert_eq!(figures.len(), names.len(), "{line}");
        for (figure, name) in figures.iter().zip(&names) {
            let rest = figure.strip_prefix(&format!("{name} ")).expect(figure);
            let (rate, ratio) = rest.split_once(" frames/s (").expect(figure);
            assert!(
                rate.parse::<f64>().is_ok() && ratio.trim_end_matches("x)").parse::<f64>().is_ok(),
                "{figure}"
            );
        }
    }
    let ratios: Vec<&str> = text.lines().filter(|l| l.starts_with("    ")).collect();
    let Some(widest) = packets.last() else {
        assert!(ratios.is_empty(), "{text}");
        return;
    };
    assert_eq!(ratios.len(), 3, "{text}");
    let w = widest.name();
    for line in ratios {
        let rest = line
            .trim_start()
            .strip_prefix(&format!("{w} f32 over {w} f64: "))
            .expect(line);
        let (ratio, target) = rest.split_once("x (").expect(line);
        assert!(ratio.parse::<f64>().is_ok(), "{line}");
        assert!(
            target.contains("); target f32 >= 1.7x the f64 packet kernel: "),
            "{line}"
        );
        assert!(
            line.ends_with(": met") || line.ends_with(": not met"),
            "{line}"
        );
    }
}
