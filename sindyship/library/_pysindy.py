"""The library terms as a pysindy feature library."""

from __future__ import annotations

import re
import warnings
from collections.abc import Sequence

import numpy as np
from pysindy.feature_library.base import BaseFeatureLibrary, x_sequence_or_item
from pysindy.utils import AxesArray, comprehend_axes
from sklearn.utils.validation import check_is_fitted

from sindyship.errors import SindyshipInputError
from sindyship.terms import CORE_VARIABLES, Term, parse_term
from sindyship.terms._term import _number_text as number_text

from ._objects import TermLibrary
from ._variables import feature_matrix


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
        """The term texts (the coefficient keys), in the names pysindy gives the inputs.

        The library binds its input columns by position to ``input_names``.  pysindy passes
        the names it gives the same columns (``SINDy.fit(..., feature_names=...)``, or a
        composed library's own names) as ``input_features``:

        - ``None``, ``input_names`` themselves, or pysindy's default names ``x0, x1, ...,
          u0, ...``: the term texts as written (the coefficient keys);
        - any other names (one per input column): the terms with each variable replaced by
          the name of its column, by position, and one :class:`UserWarning` saying so
          (names in another order than ``input_names`` mean that the columns are not bound
          as the caller thinks).

        Raises
        ------
        sklearn.exceptions.NotFittedError
            Before :meth:`fit`.

        Examples
        --------
        >>> import numpy as np
        >>> lib = AbkowitzFeatureLibrary(terms=("v^2 r", "abs(v) v"), input_names=("v", "r"))
        >>> lib = lib.fit(np.ones((3, 2)))
        >>> import warnings
        >>> with warnings.catch_warnings():
        ...     warnings.simplefilter("ignore")
        ...     lib.get_feature_names(["a", "b"])
        ['a^2 b', 'abs(a) a']
        """
        check_is_fitted(self)
        texts = [str(t) for t in self.terms_]
        if input_features is None:
            return texts
        given = [str(n) for n in input_features]
        expected = [str(n) for n in self.input_names]
        if given == expected or all(re.fullmatch(r"[xu]\d+(\[k\])?", n) for n in given):
            return texts
        if len(given) != len(expected):
            self._warn_once(
                f"{len(given)} input names were given for the library's {len(expected)} input "
                f"columns ({', '.join(expected)}); the terms are named by the library's own "
                "variables.")
            return texts
        mapping = dict(zip(expected, given, strict=True))
        renames = ", ".join(f"{a} -> {b}" for a, b in mapping.items() if a != b)
        self._warn_once(
            f"the input columns are named {given} but the library binds them by position as "
            f"{expected}; its terms are named by position ({renames}).")
        return [_renamed(term, mapping) for term in self.terms_]

    def _warn_once(self, message: str) -> None:
        """One :class:`UserWarning` per fitted library about how its names are bound."""
        if getattr(self, "_names_warned", None) != message:
            self._names_warned = message
            warnings.warn(message, UserWarning, stacklevel=3)


def _renamed(term: Term, mapping: dict[str, str]) -> str:
    """A term's text with its variables renamed (``v^2 r`` with v -> a, r -> b: ``a^2 b``)."""
    if not term.factors:
        return str(term)
    words = []
    for function, base, power in term.factors:
        name = mapping.get(base, base) if isinstance(base, str) else number_text(base)
        word = f"{function}({name})" if function else name
        words.append(word + (f"^{power}" if power > 1 else ""))
    return " ".join(words)
