(seed 002 "CACHE Beispiele" as a main program; needs file caching on in the start-up list)
N1200 #CACHE CLEAR[FILE=Laser_on.cyc]
N1210 #CACHE CLEAR ALL
N1220 #CACHE LOAD[FILE=Laser_on.cyc]
N1230 #CACHE CLEAR[FILE=Laser_on.cyc]
N1240 #CACHE LOAD[FILE=Macro.cyc]
N1250 #CACHE LOAD[FILE=Laser_off.cyc]
N1260 #CACHE LOAD[FILE=Laser_off.cyc] ; refresh cache
N1270 #CACHE LOAD[FILE=Global.sub]
N3021 L CYCLE [NAME=Laser_on.cyc @P1=0 @P2=0]
N3021 G1 X47.0000
N3022 L Global.sub
(added: use the other cached files, then end)
N3030 L CYCLE [NAME=Macro.cyc @P1=20 @P2=10]
N3040 L CYCLE [NAME=Laser_off.cyc @P1=5 @P2=0]
N3050 M30
