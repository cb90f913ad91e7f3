"""The library terms as a pysindy feature library."""

from __future__ import annotations

import re
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
from pysindy.feature_library.base import BaseFeatureLibrary, x_sequence_or_item
from pysindy.utils import AxesArray, comprehend_axes
from sklearn.utils.validation import check_is_fitted

from sindyship.errors import SindyshipInputError
from sindyship.terms import CORE_VARIABLES, Term, parse_term

from ._objects import TermLibrary
from ._variables import feature_matrix

if TYPE_CHECKING:
    pass


# ---------------------------------------------------------------------------- pysindy
class AbkowitzFeatureLibrary(BaseFeatureLibrary):
    """A pysindy feature library made of library terms (see the module docstring for use).

    Parameters
    ----------
    terms : sequence of str
        The term texts, e.g. ``library_terms = [t.text for t in library.terms["Y"]]``;
        ``Term`` objects are accepted too.  Parsed in :meth:`fit`.
    input_names : sequence of str
        The variable each input column holds, in order.  pysindy hands the library the
        state columns followed by the control columns, so for ``x = [du, v, r]`` and
        ``u = [delta]`` this is ``("du", "v", "r", "delta")``.

    Attributes
    ----------
    terms_ : tuple of Term
        The parsed terms (machine-readable through ``Term.factors``).
    n_features_in_ : int
        Number of input columns.
    n_output_features_ : int
        Number of terms.

    Examples
    --------
    >>> import numpy as np
    >>> lib = AbkowitzFeatureLibrary(terms=("v", "abs(v) v"), input_names=("v",))
    >>> lib.fit_transform(np.array([[-2.0], [3.0]]))
    AxesArray([[-2., -4.],
               [ 3.,  9.]])
    >>> lib.get_feature_names()
    ['v', 'abs(v) v']
    >>> (lib + AbkowitzFeatureLibrary(terms=("v^3",), input_names=("v",))).fit(
    ...     np.ones((2, 1))).get_feature_names()
    ['v', 'abs(v) v', 'v^3']
    """

    def __init__(
        self,
        terms: Sequence[str | Term],
        input_names: Sequence[str] = CORE_VARIABLES,
    ) -> None:
        self.terms = terms
        self.input_names = input_names

    @classmethod
    def for_dof(cls, library: TermLibrary, dof: str) -> AbkowitzFeatureLibrary:
        """The feature library of one degree of freedom of ``library``.

        Its inputs are ``library.input_names``: the state ``[du, v, r]``, then the control
        ``[delta, *sorted(channels)]``.
        """
        return cls(terms=tuple(t.text for t in library.terms[dof]), input_names=library.input_names)

    @x_sequence_or_item
    def fit(self, x_full: list[AxesArray], y: object = None) -> AbkowitzFeatureLibrary:
        """Parse the terms and check them against the inputs.

        Parameters
        ----------
        x_full : array_like, shape (n_samples, n_inputs), or a list of them
            The input data (state then control columns).
        y : ignored

        Returns
        -------
        self
        """
        n_features = x_full[0].shape[x_full[0].ax_coord]
        names = tuple(self.input_names)
        if len(names) != n_features or len(set(names)) != len(names):
            raise ValueError(
                f"input_names {names} must name each of the {n_features} input columns once."
            )
        terms = tuple(
            t if isinstance(t, Term) else parse_term(t, source="AbkowitzFeatureLibrary")
            for t in self.terms
        )
        if not terms:
            raise ValueError("AbkowitzFeatureLibrary needs at least one term.")
        for term in terms:
            missing = sorted(term.variables - set(names))
            if missing:
                raise SindyshipInputError(
                    f'the term "{term.text}" uses "{missing[0]}", which is not among the '
                    f"inputs {', '.join(names)}."
                )
        self.terms_ = terms
        self.n_features_in_ = n_features
        self.n_output_features_ = len(terms)
        return self

    @x_sequence_or_item
    def transform(self, x_full: list[AxesArray]) -> list[AxesArray]:
        """Evaluate the terms.

        Parameters
        ----------
        x_full : array_like, shape (n_samples, n_inputs), or a list of them

        Returns
        -------
        AxesArray, shape (n_samples, n_terms), or a list of them
        """
        check_is_fitted(self)
        out = []
        for x in x_full:
            if x.shape[-1] != self.n_features_in_:
                raise ValueError(
                    f"x has {x.shape[-1]} input columns; the library was fitted with "
                    f"{self.n_features_in_}."
                )
            data = np.asarray(x, dtype=float)
            values = {name: data[..., i] for i, name in enumerate(self.input_names)}
            xp = feature_matrix(self.terms_, values)
            out.append(AxesArray(xp, comprehend_axes(xp)))
        return out

    def get_feature_names(self, input_features: Sequence[str] | None = None) -> list[str]:
        """The term texts (the coefficient keys), checked against pysindy's input names.

        The library binds its input columns by ``input_names``; pysindy passes the names it
        gives the same columns (``SINDy.fit(..., feature_names=...)``) as ``input_features``.
        When they disagree the library would label its terms with the wrong variables, so it
        refuses (pysindy's default names ``x0, x1, ..., u0, ...`` name no variable and pass).

        Raises
        ------
        sklearn.exceptions.NotFittedError
            Before :meth:`fit`.
        ValueError
            When ``input_features`` are not ``input_names`` in the same order.
        """
        check_is_fitted(self)
        if input_features is not None:
            given, expected = [str(n) for n in input_features], [str(n) for n in self.input_names]
            if given != expected and not all(re.fullmatch(r"[xu]\d+", n) for n in given):
                missing = sorted(set(expected) - set(given))
                extra = sorted(set(given) - set(expected))
                what = (f"missing {missing}" if missing else "") + (
                    f"{'; ' if missing else ''}unknown {extra}" if extra else "")
                raise ValueError(
                    f"the input columns are named {given} but the library binds them as "
                    f"{expected} ({what or 'another order'}); pass input_names in the order of "
                    "the columns (state, then control) or the same feature_names to SINDy."
                )
        return [str(t) for t in self.terms_]
