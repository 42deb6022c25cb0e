use super::*;
pub(crate) fn run<const D: usize, const N: usize, const S: usize>(
    _p: &PressProblem<D, N, S>, _s: &Settings, _g: &mut dyn FnMut(Progress),
) -> Result<PressResult, PressError> where crate::element::Simplex<D, N>: crate::element::ReferenceSimplex<D, N> {
    Err(PressError::BadSettings("in progress".into()))
}
