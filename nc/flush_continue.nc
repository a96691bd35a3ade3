(seed 003 §2.3.1 "Flushing NC channel": written into the stream)
N10 G01 X200 F1000
N20 X240 Y100
N30 X200 Y0
N40 #FLUSH CONTINUE
N50 M30 (added: program end)
