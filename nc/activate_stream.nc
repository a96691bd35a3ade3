(seed 003 §2.2 "Activating streaming when the program is invoked")
(needs streaming_prog_file streaming.nc in the channel list: N40 then reads the stream)
N10 G01 X200 F1000
N20 X240 Y100
N30 X200 Y0
N40 L streaming.nc
N50 M30 (added: program end after the stream returns with M17/M29)
