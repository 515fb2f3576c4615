//! Whole takes in f64: projection and resynthesis of frames x channels matrices.

use super::{IcaModel, ModelError};
use nalgebra::DMatrix;

impl IcaModel {
    /// Projects a take, frames x channels, to its components, frames x components:
    /// `u = W (x - mean)` per frame, in f64.
    ///
    /// # Errors
    /// [`ModelError::ShapeMismatch`] when `frames` does not have `channels` columns.
    pub fn project(&self, frames: &DMatrix<f64>) -> Result<DMatrix<f64>, ModelError> {
        let n = self.channels();
        if frames.ncols() != n {
            return Err(ModelError::ShapeMismatch {
                what: "take",
                expected: (frames.nrows(), n),
                got: frames.shape(),
            });
        }
        let mut centered = frames.clone();
        for (j, mut col) in centered.column_iter_mut().enumerate() {
            col.add_scalar_mut(-self.mean[j]);
        }
        Ok(centered * self.unmixing.transpose())
    }

    /// Resynthesises a take from components, frames x components, to frames x channels:
    /// `x = mean + M u` per frame, in f64.
    ///
    /// # Errors
    /// [`ModelError::ShapeMismatch`] when `components` does not have `components` columns.
    pub fn resynthesize(&self, components: &DMatrix<f64>) -> Result<DMatrix<f64>, ModelError> {
        let m = self.components();
        if components.ncols() != m {
            return Err(ModelError::ShapeMismatch {
                what: "component series",
                expected: (components.nrows(), m),
                got: components.shape(),
            });
        }
        let mut out = components * self.mixing.transpose();
        for (j, mut col) in out.column_iter_mut().enumerate() {
            col.add_scalar_mut(self.mean[j]);
        }
        Ok(out)
    }
}
