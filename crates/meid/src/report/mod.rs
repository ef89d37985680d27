//! Reports: self-contained HTML pages assembled from studies (the paper's figures and tables,
//! or one page about a user's machine).
//!
//! The page model ([`html::Page`]) is plain data — sections holding paragraphs, figures with
//! captions and tables — rendered to one HTML file with its CSS inline. Pictures are relative
//! files beside the page (written by [`crate::plot`]), so the page opens from disk with no
//! network. [`html::check_page`] verifies a written page: every `src`/`href` to a local file
//! resolves and every figure has a caption.
//!
//! Written by hand (about 300 lines) rather than with a template engine: the page has a fixed,
//! small structure, and escaping is the only subtle part.

pub mod figures;
pub mod foundation;
pub mod histories;
pub mod html;
pub mod machine;
pub mod measured;
pub mod paper;
pub mod sketch;
pub mod testlab;
