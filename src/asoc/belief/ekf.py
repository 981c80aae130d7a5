"""The extended Kalman filter [10] (the belief dynamics of the competitor [159])."""

import numpy as np

from .. import validation as check
from .filters import checked_estimate, solve_or_pinv
from .models import NonlinearModel

__all__ = ["ekf_predict", "ekf_gain", "ekf_step"]


def _numeric_jacobians(model, x, u, w, v):
    import numdifftools as nd
    x, u, w, v = (np.asarray(z, dtype=float) for z in (x, u, w, v))
    a_x = nd.Jacobian(lambda z: model.a(z, u, w))(x)
    a_u = nd.Jacobian(lambda z: model.a(x, z, w))(u)
    a_w = nd.Jacobian(lambda z: model.a(x, u, z))(w)
    h_x = nd.Jacobian(lambda z: model.h(z, v))(x)
    h_v = nd.Jacobian(lambda z: model.h(x, z))(v)
    return tuple(np.atleast_2d(J) for J in (a_x, a_u, a_w, h_x, h_v))


def _jacobians(model, x, u, w, v):
    """(a_x, a_u, a_w, h_x, h_v): the model's analytic Jacobians, else numdifftools [46]."""
    if model.jacobians is not None:
        return model.jacobians(x, u, w, v)
    if np.asarray(x).ndim > 1:
        raise ValueError("mean: expected one state (numerical Jacobians), found a batch; "
                         "give model.jacobians")
    return _numeric_jacobians(model, x, u, w, v)


def _read_only_broadcast(vector, batch):
    """``vector`` broadcast to ``batch + vector.shape``, read-only (np.broadcast_to's result).

    Without a batch a read-only view: np.broadcast_to's argument handling costs more than
    the EKF's arithmetic on one small belief (the inner loop of [159]'s linearisation).
    """
    if batch:
        return np.broadcast_to(vector, batch + vector.shape)
    view = vector.view()
    view.flags.writeable = False
    return view


def ekf_predict(model, mean, cov, u):
    """EKF time update [10]: linearisation of a at (mean, u, E{w}); (predicted mean, Gamma).

    Broadcasts over leading axes; the arguments are not checked (see :func:`ekf_step`).

    Examples
    --------
    >>> from asoc.belief import linear_gaussian_model
    >>> model = linear_gaussian_model([[1.0]], [[1.0]], [[1.0]], [[1.0]], [[1.0]])
    >>> mean, Gamma = ekf_predict(model, np.array([1.0]), np.array([[1.0]]), np.array([0.5]))
    >>> mean.tolist(), Gamma.tolist()
    ([1.5], [[2.0]])
    """
    w0 = _read_only_broadcast(model.w.mean, mean.shape[:-1])
    v0 = _read_only_broadcast(model.v.mean, mean.shape[:-1])
    a_x, _, a_w, _, _ = _jacobians(model, mean, u, w0, v0)
    Gamma = a_x @ cov @ np.swapaxes(a_x, -1, -2) + a_w @ model.w.cov @ np.swapaxes(a_w, -1, -2)
    return model.a(mean, u, w0), Gamma


def ekf_gain(model, mean, cov):
    """EKF measurement linearisation at (mean, E{v}): y_hat, gain K, innovation and posterior cov.

    Broadcasts over leading axes; the arguments are not checked (see :func:`ekf_step`).

    Examples
    --------
    >>> from asoc.belief import linear_gaussian_model
    >>> model = linear_gaussian_model([[1.0]], [[1.0]], [[1.0]], [[1.0]], [[1.0]])
    >>> y_hat, K, S, post = ekf_gain(model, np.array([1.0]), np.array([[1.0]]))
    >>> y_hat.tolist(), K.tolist(), S.tolist(), post.tolist()
    ([1.0], [[0.5]], [[2.0]], [[0.5]])
    """
    w0 = _read_only_broadcast(model.w.mean, mean.shape[:-1])
    v0 = _read_only_broadcast(model.v.mean, mean.shape[:-1])
    u0 = np.zeros(mean.shape[:-1] + (model.n_u,))
    _, _, _, h_x, h_v = _jacobians(model, mean, u0, w0, v0)
    S = h_x @ cov @ np.swapaxes(h_x, -1, -2) + h_v @ model.v.cov @ np.swapaxes(h_v, -1, -2)
    K = solve_or_pinv(S, h_x @ cov).swapaxes(-1, -2)
    post = cov - K @ h_x @ cov
    return model.h(mean, v0), K, S, 0.5 * (post + post.swapaxes(-1, -2))


def ekf_step(model, mean, cov, u, y):
    """One step of the extended Kalman filter [10] (predict with u, update with y); broadcasts
    over leading axes.

    Parameters
    ----------
    model : NonlinearModel
        With ``a``, ``h`` and (optionally) ``jacobians``.
    mean : array_like, (..., n_x)
    cov : array_like, (..., n_x, n_x)
        Symmetric positive semi-definite.
    u : array_like, (..., n_u)
        Input applied between the estimate and the measurement.
    y : array_like, (..., n_y)
        The new measurement.

    Returns
    -------
    mean : numpy.ndarray
        The updated mean.
    cov : numpy.ndarray
        The updated covariance.

    Raises
    ------
    ValueError, TypeError
        If an argument has the wrong type or shape, or the model has no Jacobians and a
        batch of states is passed (numerical Jacobians take one state).

    Examples
    --------
    >>> from asoc.belief import linear_gaussian_model
    >>> model = linear_gaussian_model([[1.0]], [[1.0]], [[1.0]], [[1.0]], [[1.0]])
    >>> mean, cov = ekf_step(model, [0.0], [[1.0]], [0.0], [1.0])
    >>> mean.round(4).tolist(), cov.round(4).tolist()
    ([0.6667], [[0.6667]])
    """
    model = check.instance(model, NonlinearModel, "model")
    mean, cov = checked_estimate(mean, cov, "mean", "cov", model.n_x)
    u = check.real_array(u, "u")
    y = check.real_array(y, "y")
    for name, value, size in (("u", u, model.n_u), ("y", y, model.n_y)):
        if value.ndim == 0 or value.shape[-1] != size:
            raise ValueError(f"{name}: expected shape (..., {size}), found shape {value.shape}")
    mean_p, cov_p = ekf_predict(model, mean, cov, u)
    y_hat, K, _, post = ekf_gain(model, mean_p, cov_p)
    return mean_p + np.einsum("...ij,...j->...i", K, y - y_hat), post
