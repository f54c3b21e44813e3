"""`gpmotion replay`'s verdict says what the task's success test said, and
never "not solved []" for a task that has no test or states no threshold."""
from gpmotion.cli.motion import _verdict
from gpmotion.task import Task


class _NoTest(Task):
    success_threshold = ""


class _Tested(Task):
    success_threshold = "within 5 cm"

    def success(self, traj, measures):
        return None


class _TestedNoThreshold(_Tested):
    success_threshold = ""


def _task(cls):
    return object.__new__(cls)        # the verdict reads only the class


def test_a_task_without_a_success_test_says_so():
    assert _verdict(_task(_NoTest), False) == "no success test"


def test_a_tested_task_shows_its_threshold():
    assert _verdict(_task(_Tested), True) == "SOLVED  [within 5 cm]"
    assert _verdict(_task(_Tested), False) == "not solved  [within 5 cm]"


def test_no_empty_brackets_when_no_threshold_is_stated():
    assert _verdict(_task(_TestedNoThreshold), False) == "not solved"
