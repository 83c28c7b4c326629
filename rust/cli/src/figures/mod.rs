//! Figures, shared by the commands that draw: the model (`figure`), its drawing (`plot`,
//! `panels`, `distribution`), the file formats (`canvas` for PNG/SVG/PDF with `pdf`, `html` for
//! --html pages). evo's metric figures, drawn from a result, are `results::error_figures`.

pub mod canvas;
pub mod distribution;
pub mod figure;
pub mod html;
pub mod panels;
pub mod pdf;
pub mod plot;
