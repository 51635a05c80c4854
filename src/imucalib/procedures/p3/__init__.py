"""Procedure P3: accelerometer K2 on a centrifuge with dynamic-unbalance compensation.

Work in progress (issue 13): ``roundrobin`` (the reduction of the round-robin's series to K2 of
both references, the unbalance c and c′, and K2 of the test accelerometer) is built and tested
on synthetic series; the plan, the analysis of a recording and the registration are not yet.
"""
