"""Recorded channels fly as time series wherever a model flies."""

from __future__ import annotations

import numpy as np
import pytest

from sindyship._flights_compiled import STEPS_PER_REPORT
from sindyship.evaluation import evaluate
from sindyship.flights import fly_like_batch
from sindyship.library import TermLibrary
from sindyship.manoeuvres import Manoeuvre, fly
from sindyship.mmg import MMGModel
from sindyship.model import AbkowitzModel, ChannelSeries, paper_model
from sindyship.simulation import default_step
from sindyship.trajectory import Trajectory


def _with_depth(record: Trajectory, depth: np.ndarray) -> Trajectory:
    data = record.data.copy()
    data["depth"] = depth
    return Trajectory(data, name=record.name, meta=dict(record.meta))


@pytest.fixture(scope="module")
def depth_model(kcs):
    """The paper's LS model with a sway force that grows with a recorded channel."""
    base = paper_model(kcs)
    terms = {dof: [t.text for t in base.library.terms[dof]] for dof in "XYN"}
    terms["Y"].append("depth")
    library = TermLibrary("with-depth", "prime-I", "", terms)
    coefficients = {dof: dict(base.coefficients[dof]) for dof in "XYN"}
    coefficients["Y"]["depth"] = 2e-5  # per metre of the channel (scaled as given)
    return AbkowitzModel(kcs, library, coefficients)


def test_a_channel_series_interpolates_at_the_stage_times():
    series = ChannelSeries(np.array([0.0, 1.0, 2.0]), {"n": np.array([[0.0, 2.0, 2.0],
                                                                      [1.0, 1.0, 5.0]])})
    at = series.at(1.5, np.array([1, 0]))
    np.testing.assert_allclose(at["n"], [3.0, 2.0])
    np.testing.assert_allclose(series.at(-1.0, np.array([0]))["n"], [0.0])  # held at the ends


def test_a_varying_channel_flies_as_recorded_not_at_its_mean(kcs, depth_model):
    (run,) = fly(MMGModel(kcs), [Manoeuvre("turning-circle", rudder=20, duration=600)])
    ramp = _with_depth(run, np.linspace(0.0, 200.0, run.n_samples))
    flat = _with_depth(run, np.full(run.n_samples, 100.0))  # the ramp's mean, held
    (along_ramp,) = fly_like_batch(depth_model, [ramp])
    (at_mean,) = fly_like_batch(depth_model, [flat])
    gap = np.hypot(along_ramp["x"] - at_mean["x"], along_ramp["y"] - at_mean["y"]) / kcs.L
    assert gap[-1] > 0.05  # the ramp is flown, not its mean
    # two records flown together keep their own channels
    both = fly_like_batch(depth_model, [ramp, flat.with_name("flat")])
    np.testing.assert_allclose(both[0]["x"], along_ramp["x"], rtol=1e-12)
    np.testing.assert_allclose(both[1]["x"], at_mean["x"], rtol=1e-12)


def test_evaluate_flies_a_channel_model_without_being_told_the_values(kcs, depth_model):
    (run,) = fly(MMGModel(kcs), [Manoeuvre("zigzag", rudder=20, check=20, duration=400)])
    errors = evaluate(depth_model, [_with_depth(run, np.linspace(0.0, 50.0, run.n_samples))])
    assert errors[run.name]["completed"] and errors[run.name]["flown_as"] == "zigzag"


def test_channel_free_models_fly_exactly_as_before(kcs, protocol_runs):
    model = paper_model(kcs)
    direct = fly_like_batch(model.dynamics(), protocol_runs["test"])
    through = fly_like_batch(model, protocol_runs["test"])
    for a, b in zip(direct, through, strict=True):
        np.testing.assert_array_equal(a.state(), b.state())


def _replayed(record: Trajectory, n: int, name: str) -> Trajectory:
    """The record's first ``n`` samples without its command: flights replay its rudder."""
    data = record.data.iloc[:n].drop(columns=["delta_c"]).reset_index(drop=True)
    return Trajectory(data, name=name, meta=dict(record.meta))


def test_records_of_different_lengths_fly_together_as_alone(kcs, depth_model):
    (run,) = fly(MMGModel(kcs), [Manoeuvre("random", rudder=20, duration=600, seed=3)])
    run = _with_depth(run, np.linspace(0.0, 200.0, run.n_samples))
    long, short = _replayed(run, 600, "long"), _replayed(run, 250, "short")
    together = fly_like_batch(depth_model, [short, long])
    alone = [fly_like_batch(depth_model, [r])[0] for r in (short, long)]
    assert [len(f.t) for f in together] == [250, 600]
    for a, b in zip(together, alone, strict=True):
        np.testing.assert_allclose(a.state(), b.state(), rtol=1e-12, atol=1e-9)
        assert a.meta["diverged_at"] is None


def test_a_divergence_after_a_shorter_record_ends_is_not_its_own(kcs):
    model = paper_model(kcs)
    unstable = AbkowitzModel(kcs, model.library,
                             {**model.coefficients, "N": {**model.coefficients["N"], "r": 0.01}})
    (run,) = fly(MMGModel(kcs), [Manoeuvre("turning-circle", rudder=20, duration=800)])
    (alone,) = fly_like_batch(unstable, [_replayed(run, 800, "long")])
    assert alone.meta["diverged_at"] is not None
    cut = int(np.searchsorted(alone.t, alone.meta["diverged_at"])) - 5
    short, long = (fly_like_batch(unstable, [_replayed(run, cut, "short"),
                                             _replayed(run, 800, "long")]))
    assert short.meta["diverged_at"] is None and len(short.t) == cut
    assert long.meta["diverged_at"] == alone.meta["diverged_at"]
    assert np.all(np.isfinite(short["x"]))


def test_models_flown_side_by_side_fly_as_alone(kcs, depth_model, protocol_runs):
    from sindyship.flights import fly_jobs_like

    model = paper_model(kcs)
    unstable = AbkowitzModel(kcs, model.library,
                             {**model.coefficients, "N": {**model.coefficients["N"], "r": 0.01}})
    test = protocol_runs["test"]
    deep = [_with_depth(r, np.linspace(0.0, 100.0, r.n_samples)) for r in test]
    jobs = [(model, test), (unstable, test[:2]), (depth_model, deep), (model.dynamics(), test)]
    class Bar:  # what fly_jobs_like asks of a tqdm bar
        def reset(self, total):
            self.total, self.steps = total, []

        def update(self, seconds):
            self.steps.append(seconds)

    bar = Bar()
    together = fly_jobs_like(jobs, bar=bar)
    assert [len(j) for j in together] == [3, 2, 3, 3]
    # progress in seconds flown: every integration's span, in parts of at most a few
    # hundred steps (the compiled loop's reports)
    spans = [r.t[-1] - r.t[0] for r in test]
    assert max(spans) <= bar.total <= len(jobs) * max(spans)
    assert sum(bar.steps) == pytest.approx(bar.total, rel=1e-9)
    assert len(bar.steps) > 10
    assert max(bar.steps) <= STEPS_PER_REPORT * default_step(kcs) * (1 + 1e-9)
    assert any(f.meta["diverged_at"] is not None for f in together[1])
    for flights, (flier, records) in zip(together, jobs, strict=True):
        for a, b in zip(flights, fly_like_batch(flier, records), strict=True):
            np.testing.assert_array_equal(a.state(), b.state())
            assert a.meta["diverged_at"] == b.meta["diverged_at"]


def test_a_closed_loop_flight_does_not_depend_on_a_replayed_record_beside_it(kcs,
                                                                             protocol_runs):
    model = paper_model(kcs)
    zigzag = protocol_runs["test"][2]
    replayed = _replayed(protocol_runs["train"][0], zigzag.n_samples, "replayed")
    (alone,) = fly_like_batch(model, [zigzag])
    together = fly_like_batch(model, [zigzag, replayed])
    np.testing.assert_array_equal(together[0].state(), alone.state())


@pytest.mark.parametrize("compiled", [True, False])
def test_shooting_segments_fly_each_records_own_channel(kcs, depth_model, compiled,
                                                       monkeypatch):
    from sindyship.shooting import fly_segments, make_segments

    if not compiled:
        monkeypatch.setenv("SINDYSHIP_NO_COMPILE", "1")
    model = AbkowitzModel(kcs, depth_model.library,
                          {d: dict(c) for d, c in depth_model.coefficients.items()})
    (run,) = fly(MMGModel(kcs), [Manoeuvre("turning-circle", rudder=20, duration=600)])
    ramp = _with_depth(run, np.linspace(0.0, 200.0, run.n_samples))
    flat = _with_depth(run, np.full(run.n_samples, 100.0)).with_name("flat")
    (segments,) = make_segments(model, [ramp, flat], 600.0)
    assert segments.n_segments == 2 and segments.channels["depth"].shape[0] == 2
    states, _ = fly_segments(model, segments)
    # a whole-record segment replaying the actual rudder is the record's own flight
    for k, record in enumerate((ramp, flat)):
        alone = fly_like_batch(model, [_replayed(record, record.n_samples, record.name)])[0]
        rows = np.arange(1, states.shape[1] + 1) * 2  # two samples a step (0.1 L/U0)
        rows = rows[rows < record.n_samples]
        np.testing.assert_allclose(states[k, : len(rows), 3], alone["x"][rows], atol=0.5)
    gap = np.hypot(*(states[0, -1, 3:5] - states[1, -1, 3:5])) / kcs.L
    assert gap > 0.01  # the two records' channels fly apart


def test_an_effect_whose_channel_a_record_lacks_is_refused_by_name(protocol_runs):
    """A catalogued effect names the channels it needs (the record lacks one), not a term of
    its file; a term of the library's own names the library."""
    from sindyship.errors import SindyshipInputError
    from sindyship.identify import check_channels, resolve_library

    records = protocol_runs["train"][:2]
    with pytest.raises(SindyshipInputError) as caught:
        check_channels(resolve_library("abkowitz", ["wind"]), records)
    assert str(caught.value) == (
        f'the effect "wind" needs the channels "wind_speed", "wind_dir" in every record, and '
        f'record "{records[0].name}" has no "wind_dir"; add the column to the data or fit '
        "without the effect.")
    own = TermLibrary("mine", "prime-I", "", {"X": ["du"], "Y": ["v", "depth"], "N": ["r"]})
    with pytest.raises(SindyshipInputError, match='library "mine": the Y term "depth" uses the '
                       'channel "depth", which record'):
        check_channels(own, records)


def test_evaluate_names_every_record_and_channel_it_lacks_before_flying(kcs, protocol_runs):
    """``evaluate`` stopped inside the first flight of a record lacking a channel and named
    one channel of it; a user with many records learnt of the others one run at a time."""
    from sindyship.errors import SindyshipInputError
    from sindyship.identify import resolve_library

    library = resolve_library("abkowitz", ["wind"])
    paper = paper_model(kcs).coefficients
    coefficients = {dof: {t.text: paper[dof].get(t.text, 0.0) for t in library.terms[dof]}
                    for dof in ("X", "Y", "N")}
    model = AbkowitzModel(kcs, library, coefficients)
    first, second, third = protocol_runs["test"][:3]
    data = first.data.copy()
    data["wind_speed"], data["wind_dir"] = 5.0, 1.0
    full = Trajectory(data, name="full")
    data = second.data.copy()
    data["wind_speed"] = 5.0
    half = Trajectory(data, name="half")
    with pytest.raises(SindyshipInputError) as caught:
        evaluate(model, [full, half, third])
    assert str(caught.value) == (
        "the model's library reads 'wind_dir', 'wind_speed' from every record it flies, and "
        f"2 of 3 records lack some (\"half\" has no 'wind_dir'; \"{third.name}\" has no "
        "'wind_dir', 'wind_speed'); add the columns to the records, or fly them with a model "
        "fitted without the terms that use them.")
    unnamed = Trajectory(third.data, name="")
    with pytest.raises(SindyshipInputError, match=r"1 of 2 records lacks some \(record 2 has no "
                       r"'wind_dir', 'wind_speed'\)"):
        evaluate(model, [full, unnamed])
    # two records of one name had been flown and reported as one
    with pytest.raises(SindyshipInputError, match="two records share a name"):
        evaluate(model, [full, full])
    assert set(evaluate(model, [full])) == {"full"}
