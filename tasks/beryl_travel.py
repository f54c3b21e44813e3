"""beryl_travel: Beryl Biped travels to the right (Auslander et al. §2.3).

Made for time-based BSR: ``--t-per`` equal to the episode gives an aperiodic
tumble, ``--t-per`` much shorter a periodic shuffle.  Table 3 weights as in
starman_travel.
"""
from gpmotion.task import register_task
from gpmotion.tasks._travel import TravelTask


@register_task
class BerylTravel(TravelTask):
    name = "beryl_travel"
    figure = "beryl"
    description = "Beryl Biped travels right (tumble, shuffle...)"
