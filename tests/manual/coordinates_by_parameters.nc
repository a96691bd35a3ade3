; TF5200 programming manual, "Programming of coordinates by parameters"
; https://infosys.beckhoff.com/content/1033/tf5200_programming_manual/206878987.html
; adapted: N10 gives P1, P2 and a feed (machine data of the page's block); M30 appended.
; expect: end X=5
N10 P1=10 P2=1 G01 F6000
N20 XP1*SIN[P2*30]
N30 M30
