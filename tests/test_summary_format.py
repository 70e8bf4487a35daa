"""The text summary (mechgen.analyses.summary.fmt): what is cut is marked, and an output that is an object (a
law -> values map, as restitution's) shows every key, so that a reader never takes a cut for a missing entry."""
from mechgen.analyses.summary import fmt


def test_lists_are_cut_with_their_size():
    assert fmt([1.0, 2.0, 3.0], width=2) == "[1, 2, ...] (3)"
    assert fmt([1.0, 2.0], width=2) == "[1, 2]"


def test_an_output_object_shows_all_its_keys_and_cuts_its_values():
    laws = {name: [0.5, 0.25, 0.125] for name in ("a", "b", "c", "d", "e")}
    line = fmt(laws, width=2)
    assert line == "{" + ", ".join(f"{k}: [0.5, 0.25, ...] (3)" for k in "abcde") + "}"


def test_nested_objects_are_cut_like_lists_and_say_so():
    inner = {str(i): float(i) for i in range(5)}
    assert fmt([inner], width=2) == "[{0: 0, 1: 1, ...} (5)]"
    assert fmt([[inner]], width=2) == "[[{0, 1, ...} (5)]]"  # two levels down: keys only
    assert fmt({"x": [inner]}, width=8) == "{x: [{0, 1, 2, 3, 4}]}"
