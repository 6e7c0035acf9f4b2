"""Thesis listing A.3: Example usage of testing facilities using SNRTestCase and Expecter.

Printed in Appendix A (line 934 of the thesis text). A test module: run it with
``python -m unittest listing_a3`` from this folder. It tests SNR's own
``MovingAvgFilterFactory`` (``from snr import *``), not listings A.1 and A.2.

Repaired PDF artefacts: indentation, and line 20's call broken over two lines.
Deviations: none.
"""
from snr import *


class TestMovingAvgEndpoint(SNRTestCase):

    def test_moving_avg_endpoint(self):
        input_data = "input_data"
        output_data = "filtered_Data"

        expectations = {
            (TaskType.store_page, input_data): 4,
            (TaskType.process_data, input_data): 4,
            (TaskType.store_page, output_data): 4,
            (TaskType.process_data, output_data): 4,
        }
        with self.expector(expectations) as expector:
            self.run_test_node([
                ListReplayerFactory([0, 1, 2, 4], input_data),
                MovingAvgFilterFactory(input_data, output_data, 2),
                ExpecterEndpointFactory(expector,
                                        exit_when_satisfied=True),
            ])
