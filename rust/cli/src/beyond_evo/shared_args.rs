//! The options `sitar drift`, `sitar relative` and `sitar bench` have in common, declared once:
//! the Umeyama alignment (-a, -s, --n_to_align, --yaw_only) and the report (-p, --save_plot,
//! --format, -o, --html) of drift and relative, and the sub-trajectory lengths (--lengths,
//! --lengths_percent) of relative and bench. Names, short forms, aliases, defaults and the
//! flags' relations are here; each command words their help for itself (its figures and
//! files differ) in a `…Words` type, so that `--help` reads as before.

use std::marker::PhantomData;
use std::path::PathBuf;

use crate::io::output::OutputFormat;

/// A command's help for the alignment options, as `--help` shows it (no final full stop).
pub trait AlignmentWords {
    /// `-a/--align`.
    const ALIGN: &'static str;
    /// `-s/--correct_scale`.
    const CORRECT_SCALE: &'static str;
    /// `--n_to_align`.
    const N_TO_ALIGN: &'static str;
    /// `--yaw_only`.
    const YAW_ONLY: &'static str;
}

/// Umeyama alignment of the estimate to the reference before the metric.
#[derive(clap::Args, Debug)]
pub struct AlignmentArgs<W: AlignmentWords> {
    #[arg(short = 'a', long, help = W::ALIGN)]
    pub align: bool,
    #[arg(short = 's', long = "correct_scale", alias = "correct-scale", help = W::CORRECT_SCALE)]
    pub correct_scale: bool,
    #[arg(
        long = "n_to_align",
        default_value_t = -1,
        allow_negative_numbers = true,
        help = W::N_TO_ALIGN
    )]
    pub n_to_align: i64,
    #[arg(long = "yaw_only", alias = "yaw-only", requires = "align", help = W::YAW_ONLY)]
    pub yaw_only: bool,
    #[arg(skip)]
    words: PhantomData<W>,
}

/// A command's help for the report options, as `--help` shows it (no final full stop).
pub trait ReportWords {
    /// `-p/--plot`.
    const PLOT: &'static str;
    /// `--save_plot`.
    const SAVE_PLOT: &'static str;
    /// `--format`.
    const FORMAT: &'static str;
    /// `-o/--output`.
    const OUTPUT: &'static str = "Write the --format output to this file instead of stdout";
    /// `--html`.
    const HTML: &'static str;
}

/// What a metric command shows and writes besides its tables.
#[derive(clap::Args, Debug)]
pub struct ReportArgs<W: ReportWords> {
    #[arg(short = 'p', long, help = W::PLOT)]
    pub plot: bool,
    #[arg(long = "save_plot", value_name = "FILE", help = W::SAVE_PLOT)]
    pub save_plot: Option<PathBuf>,
    #[arg(long, value_enum, help = W::FORMAT)]
    pub format: Option<OutputFormat>,
    #[arg(short = 'o', long, requires = "format", help = W::OUTPUT)]
    pub output: Option<PathBuf>,
    #[arg(long, value_name = "FILE", help = W::HTML)]
    pub html: Option<PathBuf>,
    #[arg(skip)]
    words: PhantomData<W>,
}

/// A command's help for the sub-trajectory lengths, as `--help` shows it (no final full
/// stop).
pub trait LengthWords {
    /// `--lengths`.
    const LENGTHS: &'static str;
    /// `--lengths_percent`.
    const LENGTHS_PERCENT: &'static str;
}

/// Sub-trajectory lengths in metres or as percentages of the ground truth's path.
#[derive(clap::Args, Debug)]
pub struct LengthArgs<W: LengthWords> {
    #[arg(
        long,
        value_delimiter = ',',
        value_name = "METRES",
        conflicts_with = "lengths_percent",
        help = W::LENGTHS
    )]
    pub lengths: Option<Vec<f64>>,
    #[arg(
        long = "lengths_percent",
        alias = "lengths-percent",
        value_delimiter = ',',
        value_name = "PERCENT",
        help = W::LENGTHS_PERCENT
    )]
    pub lengths_percent: Option<Vec<f64>>,
    #[arg(skip)]
    words: PhantomData<W>,
}
