; TF5200 File caching, "Programming (#CACHE)": CACHE examples
; https://infosys.beckhoff.com/content/1033/tf5200_filecaching/214029323.html
; adapted: the called files are not shown on the page: here each is one block (Laser_on.cyc programs the feed the page's G1 X47 uses); M30 appended.
; expect: end X=47
; expect: runs N3022 1
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
N3030 M30
; --- file Laser_on.cyc
N10 F1000 M17
; --- file Macro.cyc
N10 M17
; --- file Laser_off.cyc
N10 M17
; --- file Global.sub
N10 M17
