"""PX4's systemlib::Hysteresis (src/lib/hysteresis), as the commander's auto-disarm uses it."""

from uavtest.sitl.hysteresis import Hysteresis


def test_a_change_needs_its_hysteresis_time_from_the_first_request():
    h = Hysteresis(False)
    h.set_hysteresis_time_from(False, 2_000_000)
    h.set_state_and_update(True, 1_000_000)
    h.set_state_and_update(True, 2_999_999)
    assert not h.state
    h.set_state_and_update(True, 3_000_000)
    assert h.state


def test_asking_for_the_current_value_cancels_the_request():
    h = Hysteresis(False)
    h.set_hysteresis_time_from(False, 2_000_000)
    h.set_state_and_update(True, 0)
    h.set_state_and_update(False, 1_500_000)
    h.set_state_and_update(True, 2_500_000)  # starts again here
    h.set_state_and_update(True, 4_000_000)
    assert not h.state
    h.set_state_and_update(True, 4_500_000)
    assert h.state


def test_without_a_time_back_the_change_back_is_immediate():
    h = Hysteresis(True)
    h.set_state_and_update(False, 10)
    assert not h.state
