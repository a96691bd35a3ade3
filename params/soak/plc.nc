(plc.nc: one printed layer in the style of a REGENHU bioprinter program, streamed)
(round and round by plc.toml. M302 waits for the tool temperature: MVS_SVS; M162)
(dispenses for its value in ms: MVS_SVS; M10 and M11 open and close a valve: MOS,)
(MNS_SNS; M12 switches the curing lamp: MVS_SLM; H2 counts the layer: MVS_SNS.)
N10 G90 G17 G01 X0 Y0 F30000
N20 M302
N30 G01 X2 Y0
N40 M162=30
N50 G01 X2 Y2
N60 M10 G01 X0 Y2
N70 M11 G01 X0 Y0
N80 M12 G00 X1 Y1
N90 G01 X1 Y0
N100 H2
N110 M30
