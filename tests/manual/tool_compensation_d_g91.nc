; TF5200 programming manual, "Tool geometry compensation": selecting D16 in G91 mode
; https://infosys.beckhoff.com/content/1033/tccncprogramming/15557086347.html
; adapted: M30 appended; the fixture's tools.lis gives tool 16 (length 60 mm, radius 2 mm).
; expect: end X=0
; expect: blocks N10 N20 N30
N10  D16
N20  G00  X0  G91
N30 M30
