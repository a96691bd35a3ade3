; TF5200 programming manual, "Synchronization of decoding and interpolation": #FLUSH WAIT
; https://infosys.beckhoff.com/content/1033/tccncprogramming/15556915851.html
; adapted: a feed rate F1000 added to N10 (the page's channel has one set), the page's "..." dropped.
; expect: end X=40
; expect: blocks N10 N20 N30
N10 G01 X20 F1000
N20 #FLUSH WAIT
N30 X40
M30
