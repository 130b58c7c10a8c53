"""Parameters: every registry entry an attribute and a keyword, checked by the registry."""

import pytest

import range_nlm


def test_every_registry_parameter_is_an_attribute_and_a_keyword():
    registry = range_nlm.Parameters.registry()
    names = [entry["name"] for entry in registry]
    assert "search_window" in names and "patch_size" in names and "cross_frame_bandwidth" in names
    recommended = range_nlm.Parameters.recommended()
    for entry in registry:
        assert getattr(recommended, entry["name"]) == entry["default"]
        assert getattr(range_nlm.Parameters.paper(), entry["name"]) == entry["paper"]
        # Setting each to its own default through the keyword is accepted.
        value = entry["default"] if entry["name"] not in ("distance_bandwidth", "similarity_bandwidth") else 0.5
        assert getattr(range_nlm.Parameters(**{entry["name"]: value}), entry["name"]) == value


def test_defaults_are_the_clis_and_the_paper_preset_is_the_papers():
    p = range_nlm.Parameters()
    assert p == range_nlm.Parameters.recommended() == range_nlm.Parameters.preset("default")
    assert (p.search_window, p.patch_size, p.iterations) == (9, 3, 2)
    paper = range_nlm.Parameters.paper()
    assert (paper.search_window, paper.patch_size, paper.iterations) == (7, 5, 1)
    assert paper.bandwidth_model == "global" and paper.displacement == "normal"
    live = range_nlm.Parameters.live()
    assert live == range_nlm.Parameters.preset("live")
    assert (live.search_window, live.patch_size, live.iterations, live.reuse_estimates) == (9, 3, 1, True)
    assert not p.reuse_estimates


def test_command_line_names_are_accepted_too():
    p = range_nlm.Parameters(patch=5, patch_gate=10.0, cross_frame="spatial")
    assert (p.patch_size, p.patch_edge_gate, p.cross_frame_bandwidth) == (5, 10.0, "spatial")


@pytest.mark.parametrize(
    "keywords, message",
    [
        ({"search_window": 4}, "parameter search_window = 4 is invalid: must be a positive odd number of pixels"),
        ({"iterations": 0}, "parameter iterations = 0 is invalid: must be 1 ... 100"),
        ({"distance_scale": -1.0}, "parameter distance_scale = -1 is invalid: must be finite and > 0"),
        ({"displacement": "sideways"}, "parameter displacement = 'sideways' is invalid: must be 'automatic'"),
        ({"distance_bandwidth": 0}, "distance_bandwidth = 0 is invalid: a bandwidth given explicitly"),
        ({"threads": 10**12}, "parameter threads = 1000000000000 is invalid"),
        ({"bandwidth_samples": 2**31 - 1},
         "parameter bandwidth_samples = 2147483647 is invalid: must be at least 1, at most 100000"),
        ({"seed": -1}, "parameter seed = -1 is invalid"),
    ],
)
def test_bad_values_raise_value_error_naming_parameter_and_value(keywords, message):
    with pytest.raises(ValueError) as error:
        range_nlm.Parameters(**keywords)
    assert message in str(error.value)


@pytest.mark.parametrize(
    "keywords, message",
    [
        ({"search_windw": 9}, "unexpected keyword argument 'search_windw'"),
        ({"search_window": 9.5}, "search_window needs an integer, got 9.5"),
        ({"patch_guide": 1}, "patch_guide needs True or False"),
        ({"bandwidth_model": 1}, "bandwidth_model needs one of 'range_adaptive' or 'global'"),
    ],
)
def test_unknown_keywords_and_wrong_types_raise_type_error(keywords, message):
    with pytest.raises(TypeError) as error:
        range_nlm.Parameters(**keywords)
    assert message in str(error.value)


def test_a_refused_attribute_leaves_the_object_as_it_was():
    p = range_nlm.Parameters()
    p.search_window = 7
    with pytest.raises(ValueError, match="search_window = 8"):
        p.search_window = 8
    assert p.search_window == 7
    assert p.replace(iterations=3).iterations == 3 and p.iterations == 2


def test_none_asks_for_the_automatic_bandwidth():
    assert range_nlm.Parameters(distance_bandwidth=None).distance_bandwidth == 0.0
