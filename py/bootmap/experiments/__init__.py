"""The experiments: the whole chain run and judged, on a simulated world (:mod:`.world`, ``bootmap
experiment WORLD``), on a real robot's log (:mod:`.log`, with :mod:`.evaluate` and :mod:`.figures`, judged
by the log's poses), and over grids of either (:mod:`.sweep`, ``bootmap sweep``). The last stage before
the service and the command line: it reads every earlier one and nothing reads it but them.
"""
