; TF5200 diagnosis, ID 20083 "Write access to tool radius is not permitted with D word in the same NC block.": the correct program (V.G.WZ_AKT.R written after D1)
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/250719627.html
; adapted: none (D1 is the fixture's tools.lis tool 1).
; expect: end X=0 Y=0 Z=0
; expect: blocks N10 N20 N30 N1000
N10 G00 X0 Y0 Z0
N20 D1
N30 V.G.WZ_AKT.R=3
N1000 M30
