"""Regression back-ends that identify the Abkowitz coefficients (paper sections 3.3-3.5).

One regression per degree of freedom: a library matrix ``X`` (one column per term, e.g. the 22
sway terms of eq. 17b) and a force target ``y`` (the right-hand side of eq. 16).  The five
estimators below are plain scikit-learn regressors, usable directly and as
``pysindy.SINDy(optimizer=...)``:

=================  ==============================================  ===========================
name               estimator                                       paper
=================  ==============================================  ===========================
``"ls"``           :class:`LeastSquares`                           section 3.3, eq. 19
``"stlsq"``        :class:`STLSQ` (Brunton et al. 2016)            (SINDy's default)
``"lasso"``        :class:`LassoCV`                                section 3.4, eq. 20
``"svr"``          :class:`SVR` (linear epsilon-SVR)               section 3.5, eq. 22-24
``"prior"``        :class:`PriorRidge` (least squares with a       (physics-consistent
                   Gaussian prior on the coefficients)             identification)
=================  ==============================================  ===========================

:func:`make_optimizer` builds one by name; :data:`OPTIMIZERS` maps the names to the classes.

Conventions shared by all five
------------------------------
No separate intercept.
    The library may contain a constant column (the term ``"1"``); its coefficient plays the
    role of the intercept.  A column is constant when its range is at most ``1e-12`` times its
    largest absolute value.  The penalised estimators (:class:`STLSQ`, :class:`LassoCV`,
    :class:`SVR`) treat the first non-zero constant column as an *unpenalised* intercept: they
    centre the other columns and the target, fit, and map the intercept back to that column's
    coefficient.  Further constant columns (duplicates, all-zero columns) get coefficient 0.
    Without a constant column nothing is centred: the model goes through the origin.
    :class:`PriorRidge` centres nothing either: every column, the constant one included, has
    its prior (the weak one unless told otherwise, which is scaled like a standardised column).
Standardised columns.
    The penalised estimators work on columns divided by their standard deviation (their root
    mean square when there is no constant column) and on the target divided by its own, so
    that one threshold, penalty or tube width means the same for ``v`` (~0.1) as for
    ``v^3`` (~1e-3) and for the surge force as for the yaw moment.  Coefficients are reported
    on the physical scale of ``X`` and ``y``.
Shapes.
    ``coef_`` always has shape ``(n_targets, n_features)``, also for a 1-D ``y`` (then
    ``(1, n_features)``): this is what ``pysindy.SINDy`` reads (it iterates over the rows of
    ``coef_``) and what pysindy's own optimizers produce.  ``predict`` returns the shape of the
    ``y`` seen in ``fit``.  Per-target hyper-parameters (``threshold_``, ``alpha_``, ``C_``,
    ``epsilon_``) are arrays of shape ``(n_targets,)``.
Cross-validation.
    ``fit(X, y, groups=None)``.  ``cv=None`` (the default) means leave-one-group-out when
    ``groups`` is given (one group per manoeuvre: a held-out manoeuvre shares no samples with
    the training set; samples labelled ``ALWAYS_TRAINED``, -1, such as a hybrid fit's captive
    conditions, are in every training set and never held out) and 5 contiguous, unshuffled
    blocks (``KFold(5, shuffle=False)``) when it is not, with a ``UserWarning`` that says so.
    ``pysindy.SINDy.fit`` calls ``fit(X, y)``
    without groups: give the optimizer ``cv=LeaveOneTrajectoryOut(lengths)``, the number of
    samples of every trajectory in the order ``SINDy.fit`` gets them, to leave one manoeuvre
    out there too.  An integer ``cv=k`` means ``k`` contiguous blocks, whatever ``groups`` is; the
    paper's 10-fold cross-validation is ``cv=10`` (MATLAB shuffles its folds: pass
    ``cv=KFold(10, shuffle=True, random_state=seed)`` for that, and note that on noise-free
    1 Hz data shuffled folds leak neighbouring samples and pick almost no regularisation).
    Any scikit-learn splitter or iterable of ``(train, test)`` index pairs is accepted too;
    ``groups`` is handed to its ``split``.  The splitter used is stored in ``cv_``.  The
    cross-validation error is the mean over folds of the held-out mean squared error, in the
    units of ``y`` squared.  Errors within ``1e-12`` relatively of the smallest, or below
    ``1e-20`` times the target's mean square (rounding on noise-free data), count as ties,
    which go to the more regularised candidate.
Parameters are JSON-serialisable by default (strings, numbers, ``None``, lists), so a saved
model can record ``{"name": ..., "params": estimator.get_params()}``.  Randomness enters only
through ``random_state`` (used by :class:`SVR` with ``solver="liblinear"``); everything else
is deterministic.

Layout
------
One algorithm per private module, the public names re-exported here:
``_least_squares`` (:class:`LeastSquares`), ``_stlsq`` (:class:`STLSQ`), ``_lasso``
(:class:`LassoCV` and its exact homotopy path), ``_svr`` (:class:`SVR` and its Newton
solver), ``_prior`` (:class:`PriorRidge`; :mod:`sindyship.priors` gives it a ship's prior).
``_base`` holds ``_LinearModel``, whose ``fit`` template validates the input, makes
the folds and calls the estimator's ``_reduce`` hook (a new estimator subclasses it and
implements the hook); ``_compressed`` the one QR-compression engine, also public as
:class:`GroupedProblem` (least-squares refits of column subsets leaving one record out);
``_factored`` the fit data of :meth:`_LinearModel.fit_factors`, which fits ``ls``, ``stlsq``
and ``lasso`` from one :class:`RowFactor` per record instead of the rows (records reduced on
the workers of a cluster, merged as a tree: :func:`merge_factors`, :func:`tree_factor`);
``_cv`` the cross-validation choices; ``_standardise`` the intercept and scaling conventions
above; ``_threads`` the :func:`one_blas_thread` guard; ``_registry`` :func:`make_optimizer`.
"""

from __future__ import annotations

# Private names are re-exported (``name as name``) for the modules and tests using them.
from ._base import _LinearModel as _LinearModel
from ._compressed import GroupedProblem, RowFactor, merge_factors, pairwise_tree, tree_factor
from ._compressed import _qr as _qr
from ._cv import ALWAYS_TRAINED, LeaveOneTrajectoryOut
from ._forward import ForwardSelection
from ._lasso import LassoCV
from ._lasso import _lasso_path_exact as _lasso_path_exact
from ._least_squares import LeastSquares
from ._prior import PriorRidge
from ._registry import OPTIMIZERS, make_optimizer
from ._standardise import _column_roles as _column_roles
from ._standardise import _Standardiser as _Standardiser
from ._stlsq import STLSQ
from ._svr import SVR
from ._svr import _svr_newton as _svr_newton
from ._svr import _svr_objective as _svr_objective
from ._svr import _with_ones as _with_ones
from ._threads import one_blas_thread

__all__ = [
    "ALWAYS_TRAINED",
    "OPTIMIZERS",
    "STLSQ",
    "ForwardSelection",
    "SVR",
    "GroupedProblem",
    "RowFactor",
    "LassoCV",
    "LeastSquares",
    "LeaveOneTrajectoryOut",
    "PriorRidge",
    "make_optimizer",
    "merge_factors",
    "one_blas_thread",
    "pairwise_tree",
    "tree_factor",
]
