; TF5200 programming manual, "Counting loop ($FOR)": negative increment
; https://infosys.beckhoff.com/content/1033/tf5200_programming_manual/206929163.html
; adapted: N90 G01 F6000 added; the page's N130 "..." dropped; M30 appended.
; expect: runs N110 46
; expect: end X=0.766044 Y=0.642788
N90 G01 F6000
N100 $FOR P1= 100, 10, -2 (P1 is pre-assigned 100; the loop runs until P1 falls below 10)
N110 X SIN [P1 * 5]
N120 Y COS [P1 * 5]
N150 $ENDFOR
N160 M30
