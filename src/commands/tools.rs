//! The commands around the pipeline: `preview`, `measure` and `bench` run the tools.

use super::{Error, beside_frames, out, shown};
use crate::cli::{BenchArgs, MeasureArgs, PreviewArgs};
use crate::console::{self, printable};
use crate::output;
use crate::sequence;
use crate::tools::measure;

/// Writes DIR/NAME_path.png and DIR/NAME_sheet.png, printing their paths; warnings about the
/// camera path go to stderr. A path whose camera cannot be built somewhere is still drawn,
/// with the reason, and then reported as the load error it is (exit 2).
pub(super) fn preview(args: PreviewArgs) -> Result<(), Error> {
    use crate::tools::preview;
    let (seq, problem) = sequence::load_drawable(&args.file, &super::assets(&args.assets)?)?;
    let (first, last) = (seq.timeline.first_frame(), seq.timeline.last_frame());
    let frames: Vec<u64> = match &args.frames {
        Some(spec) => {
            let set = spec
                .frames(first, last)
                .map_err(|e| Error::Usage(format!("--frames: {e}")))?;
            if set.len() > preview::MAX_TILES {
                return Err(Error::Usage(format!(
                    "--frames: {} frames; a contact sheet holds at most {}",
                    set.len(),
                    preview::MAX_TILES
                )));
            }
            set.iter().collect()
        }
        None => crate::frameset::evenly_spaced(seq.timeline.frame_count, args.tiles)
            .into_iter()
            .map(|n| n + first)
            .collect(),
    };
    let dir = args.out.unwrap_or_else(|| beside_frames(&seq, "preview"));
    std::fs::create_dir_all(&dir)
        .map_err(|e| Error::Failed(format!("{}: cannot create directory: {e}", dir.display())))?;
    let reason = problem.as_ref().map(|p| p.to_string());
    let (plot, warnings) = preview::path_plot(&seq, reason.as_deref());
    for w in seq.warnings.iter().chain(&warnings) {
        eprintln!("warning: {}", printable(w));
    }
    let plot_file = dir.join(format!("{}_path.png", seq.name));
    preview::write_png(&plot_file, &plot).map_err(|e| Error::Failed(e.to_string()))?;
    out(&format!("{}\n", shown(&plot_file)))?;
    let (sheet, _) = preview::contact_sheet(&seq, &frames, preview::TILE_WIDTH)
        .map_err(|e| Error::Failed(e.to_string()))?;
    let sheet_file = dir.join(format!("{}_sheet.png", seq.name));
    preview::write_png(&sheet_file, &sheet).map_err(|e| Error::Failed(e.to_string()))?;
    out(&format!("{}\n", shown(&sheet_file)))?;
    problem.map_or(Ok(()), |p| Err(Error::Load(p)))
}

pub(super) fn measure(args: MeasureArgs) -> Result<(), Error> {
    let mut seq = sequence::load_with(&args.file, &super::assets(&args.assets)?)?;
    let (first, last) = (seq.timeline.first_frame(), seq.timeline.last_frame());
    if !(first..=last).contains(&args.frame) {
        return Err(Error::Usage(format!(
            "--frame: frame {} is outside the timeline, which has frames {first}-{last}",
            args.frame
        )));
    }
    let (w, h) = match args.size {
        Some(size) => size,
        None => {
            let s = &seq.settings;
            (
                320,
                (320.0 * f64::from(s.height) / f64::from(s.width))
                    .round()
                    .max(1.0) as u32,
            )
        }
    };
    (seq.settings.width, seq.settings.height) = (w, h);
    if let Some(e) = args.encoding {
        seq.settings.encoding = e;
    }
    let dir = args
        .out
        .clone()
        .unwrap_or_else(|| beside_frames(&seq, "measure"));
    std::fs::create_dir_all(&dir)
        .map_err(|e| Error::Failed(format!("{}: cannot create directory: {e}", dir.display())))?;
    eprintln!(
        "measuring frame {} of {} at {w}x{h}",
        args.frame,
        shown(&args.file)
    );
    let options = measure::Options {
        reference: measure::reference::Options {
            samples: args.reference_samples,
            depth: args.reference_depth,
            check_samples: args.check_samples,
            cache: args.reference_cache,
        },
        only: args.only,
    };
    let report = measure::measure(
        &seq,
        args.frame,
        args.runs as usize,
        &options,
        &mut |line| eprintln!("  {line}"),
    )?;
    out(&report.table())?;
    for (name, bytes) in [
        ("measure.csv", report.csv().into_bytes()),
        ("measure.json", report.json().into_bytes()),
        ("measure.svg", report.svg().into_bytes()),
        ("reference.png", report.reference_png()),
    ] {
        let path = dir.join(name);
        output::atomic::write_atomic(&path, &bytes)
            .map_err(|e| Error::Failed(format!("{}: cannot write: {e}", path.display())))?;
        eprintln!("wrote {}", shown(&path));
    }
    Ok(())
}

pub(super) fn bench(args: BenchArgs) -> Result<(), Error> {
    let options = crate::tools::bench::Options {
        runs: args.runs as usize,
        only: args.only,
        quick: args.quick,
    };
    // A reader that has gone ends the output, not the benchmark's own error reporting.
    crate::tools::bench::run(&options, &mut |line| {
        let _ = console::print(&format!("{line}\n"));
    })
    .map_err(|e| Error::Failed(e.to_string()))
}
